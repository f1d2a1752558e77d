//! Lane kernels: code written as loops over fixed-size arrays of [`LANES`] values, which LLVM
//! turns into vector instructions, and a run-time choice of the widest instruction set the CPU
//! has to compile them for. Without `-C target-cpu`, Rust targets baseline x86-64 (SSE2, 4 f32
//! lanes); [`widest`] runs its closure as AVX-512 or AVX2 code where the CPU has them.
//!
//! Results do not depend on the choice: Rust never contracts a * b + c into an FMA, and the
//! vector forms of +, -, *, / and sqrt round exactly as the scalar ones do.
//!
//! What LLVM vectorises across lanes, as measured in this crate's kernels:
//! - loops over all lanes with one step of the computation each (`for l in 0..LANES { d[l] =
//!   ... }`), not one loop holding a whole per-lane computation, which it vectorised across
//!   x, y, z instead, if at all;
//! - lane arrays of plain numbers: copying `Option`s or structs of mixed field sizes between lane
//!   arrays stalls on store-to-load forwarding, and a `match` per lane keeps a loop scalar (pass
//!   the variant's test in as a closure, as `geometry::flat_lanes` does).

use glam::Vec3;

mod transpose;
pub use transpose::{store_rgb_spectra, store_vec3s};

/// Values per lane array: one AVX-512 register of f32.
pub const LANES: usize = 16;

/// The `LANES` values of `column` from `first`, as an array: loads of a length known at compile
/// time (no bounds checks in lane loops). Panics if fewer remain.
#[inline(always)]
pub fn block<T>(column: &[T], first: usize) -> &[T; LANES] {
    column[first..].first_chunk().expect("a whole block")
}

/// [`block`] for writing: stores of a length known at compile time.
#[inline(always)]
pub fn block_mut<T>(column: &mut [T], first: usize) -> &mut [T; LANES] {
    column[first..].first_chunk_mut().expect("a whole block")
}

/// Lane columns (x, y, z) as `LANES` vectors: a loop of this one step becomes a few vector
/// shuffles, where a loop that also computes the values stays scalar. How well LLVM does it
/// depends on the kernel: the camera pass measured fastest with this, the sampling pass with
/// [`store_vec3s`] (explicit AVX-512 permutes).
#[inline(always)]
pub fn vec3s(c: &[[f32; LANES]; 3]) -> [Vec3; LANES] {
    let mut out = [Vec3::ZERO; LANES];
    for l in 0..LANES {
        out[l] = Vec3::new(c[0][l], c[1][l], c[2][l]);
    }
    out
}

/// The lane columns (all x, all y, all z) of `LANES` vectors, [`vec3s`] inverted: read from the
/// block as one run of floats, which LLVM loads as whole registers and shuffles, where reading
/// `v[l].x` lane by lane made scalar loads and stores that stalled the vector loads after them.
#[inline(always)]
pub fn columns(v: &[Vec3; LANES]) -> [[f32; LANES]; 3] {
    // SAFETY: `Vec3` is `#[repr(C)]` of three f32 (no padding), so the block is 3 * LANES f32.
    let flat: &[f32; 3 * LANES] = unsafe { &*(v as *const [Vec3; LANES]).cast() };
    let mut c = [[0.0f32; LANES]; 3];
    for l in 0..LANES {
        for a in 0..3 {
            c[a][l] = flat[3 * l + a];
        }
    }
    c
}

/// Runs `f` compiled for AVX-512 or AVX2 when the CPU has them (else as it is). Only the code
/// inlined into the wrapper is compiled for the wider set, and LLVM does not inline a large
/// closure on its own: mark `f` `#[inline(always)]` (attributes on closures are stable), and the
/// lane kernels it calls too. Loops over iterator adapters (`step_by`, `array::from_fn`) may stay
/// out of line; plain `for` loops over indices do not.
#[inline]
pub fn widest<R>(f: impl FnOnce() -> R) -> R {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f")
            && std::arch::is_x86_feature_detected!("avx512dq")
            && std::arch::is_x86_feature_detected!("avx512vl")
            && std::arch::is_x86_feature_detected!("avx512bw")
        {
            // SAFETY: the CPU has every feature the function is compiled for (checked above).
            return unsafe { x86::avx512(f) };
        }
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: as above, for AVX2.
            return unsafe { x86::avx2(f) };
        }
    }
    f()
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    #[target_feature(enable = "avx512f,avx512dq,avx512vl,avx512bw,avx2,avx,sse4.2,popcnt,bmi1,bmi2,lzcnt")]
    pub unsafe fn avx512<R>(f: impl FnOnce() -> R) -> R {
        f()
    }

    #[target_feature(enable = "avx2,avx,sse4.2,popcnt,bmi1,bmi2,lzcnt")]
    pub unsafe fn avx2<R>(f: impl FnOnce() -> R) -> R {
        f()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn widest_runs_the_closure_once_and_returns_its_value() {
        let mut calls = 0;
        let v = widest(|| {
            calls += 1;
            (0..LANES).map(|i| (i as f32).sqrt()).sum::<f32>()
        });
        assert_eq!(calls, 1);
        assert_eq!(v, (0..LANES).map(|i| (i as f32).sqrt()).sum::<f32>());
    }

    #[test]
    fn columns_undo_vec3s() {
        let c: [[f32; LANES]; 3] = std::array::from_fn(|a| std::array::from_fn(|l| (100 * a + l) as f32 - 0.5));
        let v = vec3s(&c);
        assert_eq!(v[5], Vec3::new(4.5, 104.5, 204.5));
        assert_eq!(columns(&v), c);
        assert_eq!(widest(|| columns(&v)), c);
    }
}

//! Whole blocks of `LANES` lane columns (all x, all y, all z) stored into columns of vectors
//! (x, y, z interleaved). Entry stores made lane by lane dominated the sampling pass, and LLVM's
//! vectoriser, left to itself, rebuilds the interleaving from scalars inside large kernels. With AVX-512 a block is a few registers moved by two-source permutes;
//! elsewhere, lane by lane.
//!
//! The AVX-512 code sits in `#[target_feature]` functions, which only code compiled for AVX-512
//! may inline; elsewhere they are calls. They run where [`widest`](super::widest) runs at
//! AVX-512, whose features include everything theirs imply. Use them at the end of a block, when few vector
//! registers are live: loads made this way at the start of a kernel measured slower than scalar
//! loads.

use glam::Vec3;

use super::LANES;
use crate::spectrum::SampledSpectrum;

/// Whether the CPU has every feature the `avx512` functions are compiled with: AVX-512F and what
/// it implies (AVX2, FMA, F16C, AVX, SSE4.2 and down), all among the features of
/// [`Level::Avx512`](super::Level), which is in use only if the CPU has each of them.
#[inline(always)]
fn has_avx512() -> bool {
    super::level() == super::Level::Avx512
}

/// `out[l] = (c[0][l], c[1][l], c[2][l])`.
#[inline(always)]
pub fn store_vec3s(c: &[[f32; LANES]; 3], out: &mut [Vec3; LANES]) {
    #[cfg(target_arch = "x86_64")]
    if has_avx512() {
        // SAFETY: the CPU has AVX-512F and all it implies (checked above); `Vec3` is three f32,
        // so `out` is 48.
        return unsafe { avx512::store3(c, out.as_mut_ptr().cast()) };
    }
    portable::store_vec3s(c, out)
}

/// `out[l] = [c[0][l], c[1][l], c[2][l], 0]`: RGB lane columns as spectra.
#[inline(always)]
pub fn store_rgb_spectra(c: &[[f32; LANES]; 3], out: &mut [SampledSpectrum; LANES]) {
    #[cfg(target_arch = "x86_64")]
    if has_avx512() {
        // SAFETY: the CPU has AVX-512F and all it implies (checked above); `SampledSpectrum` is
        // a transparent [f32; 4], so `out` is 64 f32.
        return unsafe { avx512::store4(c, out.as_mut_ptr().cast()) };
    }
    portable::store_rgb_spectra(c, out)
}

/// The same stores lane by lane, for CPUs without AVX-512.
mod portable {
    use super::*;

    #[inline(always)]
    pub(super) fn store_vec3s(c: &[[f32; LANES]; 3], out: &mut [Vec3; LANES]) {
        *out = crate::lanes::vec3s(c);
    }

    #[inline(always)]
    pub(super) fn store_rgb_spectra(c: &[[f32; LANES]; 3], out: &mut [SampledSpectrum; LANES]) {
        for l in 0..LANES {
            out[l] = SampledSpectrum([c[0][l], c[1][l], c[2][l], 0.0]);
        }
    }
}

#[cfg(target_arch = "x86_64")]
mod avx512 {
    use std::arch::x86_64::*;

    use super::LANES;

    /// Permute indices that interleave `width`-float vectors from columns x, y, z (a fourth
    /// component, if any, is zeroed by a mask): for output register k, the first step takes x
    /// and y from registers x (indices 0..16) and y (16..32); the second keeps those (0..16) and
    /// takes z from register z (16..32). Float j of the block is component j % width of lane
    /// j / width.
    const fn interleave(width: usize, k: usize) -> [[i32; 16]; 2] {
        let (mut xy, mut z, mut i) = ([0; 16], [0; 16], 0);
        while i < 16 {
            let j = 16 * k + i;
            let (lane, component) = ((j / width) as i32, j % width);
            xy[i] = if component == 1 { 16 + lane } else { lane };
            z[i] = if component == 2 { 16 + lane } else { i as i32 };
            i += 1;
        }
        [xy, z]
    }

    const STORE3: [[[i32; 16]; 2]; 3] = [interleave(3, 0), interleave(3, 1), interleave(3, 2)];
    const STORE4: [[[i32; 16]; 2]; 4] = [interleave(4, 0), interleave(4, 1), interleave(4, 2), interleave(4, 3)];
    /// Every fourth float (the spectra's unused fourth value) off.
    const XYZ_OF_4: __mmask16 = 0x7777;

    #[inline]
    #[target_feature(enable = "avx512f")]
    fn indices(i: &[i32; 16]) -> __m512i {
        // SAFETY: 16 i32 are 64 bytes; unaligned loads are allowed.
        unsafe { _mm512_loadu_si512(i.as_ptr().cast()) }
    }

    #[inline]
    #[target_feature(enable = "avx512f")]
    fn columns(c: &[[f32; LANES]; 3]) -> [__m512; 3] {
        // SAFETY: each column is 16 f32 (64 bytes); unaligned loads are allowed.
        [0, 1, 2].map(|a| unsafe { _mm512_loadu_ps(c[a].as_ptr()) })
    }

    /// Stores 48 floats at `dst`.
    ///
    /// # Safety
    /// `dst` must be valid for writes of 48 f32.
    #[target_feature(enable = "avx512f")]
    pub(super) unsafe fn store3(c: &[[f32; LANES]; 3], dst: *mut f32) {
        let [x, y, z] = columns(c);
        for (k, [xy, zi]) in STORE3.iter().enumerate() {
            let t = _mm512_permutex2var_ps(x, indices(xy), y);
            // SAFETY: register k covers floats 16k..16k + 16 of the 48 (caller's contract).
            unsafe { _mm512_storeu_ps(dst.add(16 * k), _mm512_permutex2var_ps(t, indices(zi), z)) };
        }
    }

    /// Stores 64 floats at `dst`, every fourth zero.
    ///
    /// # Safety
    /// `dst` must be valid for writes of 64 f32.
    #[target_feature(enable = "avx512f")]
    pub(super) unsafe fn store4(c: &[[f32; LANES]; 3], dst: *mut f32) {
        let [x, y, z] = columns(c);
        for (k, [xy, zi]) in STORE4.iter().enumerate() {
            let t = _mm512_permutex2var_ps(x, indices(xy), y);
            let v = _mm512_maskz_permutex2var_ps(XYZ_OF_4, t, indices(zi), z);
            // SAFETY: register k covers floats 16k..16k + 16 of the 64 (caller's contract).
            unsafe { _mm512_storeu_ps(dst.add(16 * k), v) };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_avx512_stores_check_every_feature_avx512f_implies() {
        // What `rustc --print cfg -C target-feature=+avx512f` adds to the x86-64 baseline.
        let implied = ["avx512f", "avx2", "avx", "fma", "f16c", "sse4.2", "sse4.1", "ssse3", "sse3"];
        for f in implied {
            assert!(crate::lanes::Level::Avx512.features().contains(&f), "{f}");
        }
    }

    #[test]
    fn block_stores_match_lane_by_lane_stores() {
        let c: [[f32; LANES]; 3] = std::array::from_fn(|a| std::array::from_fn(|l| (100 * a + l) as f32 - 0.5));
        type Stores =
            (fn(&[[f32; LANES]; 3], &mut [Vec3; LANES]), fn(&[[f32; LANES]; 3], &mut [SampledSpectrum; LANES]));
        let dispatched: Stores = (store_vec3s, store_rgb_spectra);
        let portable: Stores = (portable::store_vec3s, portable::store_rgb_spectra);
        // The portable code, and the dispatched code called from plain code and from code compiled
        // for the widest instruction set (where AVX-512 code may inline).
        for ((vec3s, spectra), wide) in [(portable, false), (dispatched, false), (dispatched, true)] {
            let (mut v, mut rgb) = ([Vec3::NAN; LANES], [SampledSpectrum([f32::NAN; 4]); LANES]);
            let mut run = || {
                vec3s(&c, &mut v);
                spectra(&c, &mut rgb);
            };
            if wide {
                crate::lanes::widest(run)
            } else {
                run()
            }
            for l in 0..LANES {
                assert_eq!(v[l].to_array(), [c[0][l], c[1][l], c[2][l]], "lane {l}");
                assert_eq!(rgb[l].0, [c[0][l], c[1][l], c[2][l], 0.0], "lane {l}");
            }
        }
    }
}

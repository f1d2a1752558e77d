//! Lane kernels: code written over the lane types [`F32x16`], [`U32x16`], [`Mask16`] and
//! [`Vec3x16`] (`LANES` values each), whose every operation is a loop over a fixed-size array that
//! LLVM turns into vector instructions, and a run-time choice of the widest instruction set the
//! CPU has to compile them for. Without `-C target-cpu`, Rust targets baseline x86-64 (SSE2, 4 f32
//! lanes); `widest` runs its closure as AVX-512 or AVX2 code where the CPU has every feature
//! that code is compiled with (`Level`).
//!
//! Results do not depend on the choice: Rust never contracts a * b + c into an FMA, and the
//! vector forms of +, -, *, / and sqrt round exactly as the scalar ones do.
//!
//! What LLVM vectorises across lanes, as measured in this crate's kernels:
//! - loops over all lanes with one step of the computation each (`for l in 0..LANES { d[l] =
//!   ... }`), not one loop holding a whole per-lane computation, which it vectorised across
//!   x, y, z instead, if at all;
//! - lane arrays of plain numbers: copying `Option`s or structs of mixed field sizes between lane
//!   arrays stalls on store-to-load forwarding, and a `match` per lane keeps a loop scalar.

pub mod math;
mod real;
mod types;

pub use real::{Real, Real3, Vector};
pub use types::{F32x16, Mask16, U32x16, Vec3x16};

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

/// Runs `f` compiled for the widest instruction set the CPU has ([`level`]: AVX-512 or AVX2,
/// else as it is). Only the code inlined into the wrapper is compiled for the wider set, and LLVM
/// does not inline a large closure on its own: mark `f` `#[inline(always)]` (attributes on
/// closures are stable), and the lane kernels it calls too. Loops over iterator adapters
/// (`step_by`, `array::from_fn`) may stay out of line; plain `for` loops over indices do not.
#[inline]
pub fn widest<R>(f: impl FnOnce() -> R) -> R {
    let level = level();
    // SAFETY: `level()` is a level whose every feature the CPU has (see `choose`).
    unsafe { run_at(level, f) }
}

/// The instruction-set levels [`widest`] may run its closure at, widest first, each with every
/// target feature its wrapper is compiled with. One list per level makes both the wrapper's
/// `#[target_feature]` attributes and what [`level`] checks before choosing it, so the two cannot
/// drift apart. The lists spell out what the features named imply (`rustc --print cfg -C
/// target-feature=+avx512f` shows avx512f bringing avx2, fma and f16c, avx2 bringing avx, and so
/// down to sse3): the wrapper is compiled with those too, so they are checked too.
macro_rules! levels {
    ($($(#[$doc:meta])* $level:ident => $wrapper:ident [$($feature:tt),+ $(,)?];)+) => {
        /// An instruction-set level of [`widest`].
        #[derive(Clone, Copy, Debug, PartialEq, Eq)]
        pub enum Level {
            $($(#[$doc])* $level,)+
            /// The target's baseline (SSE2 on x86-64 without `-C target-cpu`): `f` as compiled.
            Baseline,
        }

        impl Level {
            /// Every level, widest first.
            pub const ALL: &[Level] = &[$(Level::$level,)+ Level::Baseline];

            /// The target features this level's code is compiled with, and the CPU must have.
            pub const fn features(self) -> &'static [&'static str] {
                match self {
                    $(Level::$level => &[$($feature),+],)+
                    Level::Baseline => &[],
                }
            }
        }

        #[cfg(target_arch = "x86_64")]
        mod x86 {
            $(
                /// Runs `f` compiled with the features of the level of the same name.
                ///
                /// # Safety
                /// The CPU must have every one of them.
                $(#[target_feature(enable = $feature)])+
                pub unsafe fn $wrapper<R>(f: impl FnOnce() -> R) -> R {
                    f()
                }
            )+
        }

        /// Runs `f` through the wrapper of `level`.
        ///
        /// # Safety
        /// The CPU must have every feature of `level`.
        #[inline(always)]
        unsafe fn run_at<R>(level: Level, f: impl FnOnce() -> R) -> R {
            match level {
                // SAFETY: the caller's contract.
                $(#[cfg(target_arch = "x86_64")] Level::$level => unsafe { x86::$wrapper(f) },)+
                _ => f(),
            }
        }

        /// Whether the CPU has `feature` (and the OS supports it), for the features the levels
        /// name; None for any other (and on other architectures).
        fn cpu_has(feature: &str) -> Option<bool> {
            #[cfg(target_arch = "x86_64")]
            #[allow(unreachable_patterns)] // a feature of several levels is tested where first named
            match feature {
                $($($feature => return Some(std::arch::is_x86_feature_detected!($feature)),)+)+
                _ => {}
            }
            let _ = feature;
            None
        }
    };
}

levels! {
    /// AVX-512 (F, DQ, VL, BW) with AVX2 and the scalar extensions of x86-64-v3.
    Avx512 => avx512 [
        "avx512f", "avx512dq", "avx512vl", "avx512bw", "avx2", "avx", "fma", "f16c",
        "sse4.2", "sse4.1", "ssse3", "sse3", "popcnt", "bmi1", "bmi2", "lzcnt",
    ];
    /// AVX2 with the scalar extensions of x86-64-v3.
    Avx2 => avx2 ["avx2", "avx", "sse4.2", "sse4.1", "ssse3", "sse3", "popcnt", "bmi1", "bmi2", "lzcnt"];
}

/// Runs `f` compiled for `level` (as [`widest`] does for the widest), or None if the CPU lacks
/// a feature of it: for tests that compare a kernel's results across levels.
pub fn at_level<R>(level: Level, f: impl FnOnce() -> R) -> Option<R> {
    let has_all = level.features().iter().all(|feature| cpu_has(feature) == Some(true));
    // SAFETY: the CPU has every feature of `level`.
    has_all.then(|| unsafe { run_at(level, f) })
}

/// The widest level for which `has` reports every feature (as `Some(true)`).
fn choose(has: impl Fn(&str) -> Option<bool>) -> Level {
    let every = |l: &&Level| l.features().iter().all(|f| has(f) == Some(true));
    *Level::ALL.iter().find(every).expect("the baseline needs no feature")
}

/// The level [`widest`] runs at on this CPU: the widest whose every feature it has, detected once.
#[inline]
pub fn level() -> Level {
    static LEVEL: std::sync::OnceLock<Level> = std::sync::OnceLock::new();
    *LEVEL.get_or_init(|| choose(cpu_has))
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
    fn a_level_is_chosen_only_if_the_cpu_has_every_feature_its_code_is_compiled_with() {
        assert_eq!(choose(|_| Some(true)), Level::ALL[0], "every feature present: the widest level");
        assert_eq!(choose(|_| Some(false)), Level::Baseline);
        for &level in Level::ALL {
            for &missing in level.features() {
                // A CPU with every feature but `missing` gets the widest level compiled without it.
                let chosen = choose(|f| Some(f != missing));
                let want = Level::ALL.iter().copied().find(|l| !l.features().contains(&missing));
                assert_eq!(Some(chosen), want, "without {missing} (a feature of {level:?})");
                // A feature the detector cannot tell about counts as missing.
                assert_eq!(choose(|f| (f != missing).then_some(true)), chosen, "{missing} unknown");
            }
        }
    }

    #[test]
    fn the_detector_knows_every_feature_and_the_level_in_use_has_them_all() {
        for &level in Level::ALL {
            for &f in level.features() {
                assert!(cpu_has(f).is_some(), "{level:?}: the detector does not know {f}");
            }
        }
        assert!(cpu_has("no-such-feature").is_none());
        let level = level();
        for &f in level.features() {
            assert_eq!(cpu_has(f), Some(true), "{level:?} in use without {f}");
        }
    }
}

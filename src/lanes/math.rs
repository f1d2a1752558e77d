//! Elementary f32 functions, branch-free so that they vectorise (std's `exp`, `atan2` and
//! `sin_cos` are libm calls, one lane at a time): `exp` over lane arrays, one loop per step over
//! the lanes (see the parent module), and `atan2_pos` and `sin_cos_0_pi` written once over
//! [`Real`], so that scalar code and lane kernels get the same bits. Each is accurate to a few
//! ulps, not correctly rounded (the tests measure it).

use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};

use super::{F32x16, LANES, Real};

/// e^x per lane, for x clamped to [-87, 88] (e^-87 = 1.6e-38 is the smallest result: no
/// subnormals, no zero). Relative error under 2.5e-7 (3 ulps), measured in the tests.
#[inline(always)]
pub fn exp(x: F32x16) -> F32x16 {
    let x = &x.0;
    // Cephes expf (S. L. Moshier, cephes/single/expf.c): x = n ln 2 + r, |r| <= ln 2 / 2, ln 2 in
    // two parts (C1 exact in 9 bits, so n C1 is exact) and a degree-7 polynomial for e^r.
    const C1: f32 = 0.693_359_4;
    const C2: f32 = -2.121_944_4e-4;
    const P: [f32; 6] = [1.987_569_1e-4, 1.398_199_9e-3, 8.333_452e-3, 4.166_579_6e-2, 0.166_666_65, 0.5];
    // 1.5 * 2^23: adding it rounds to an integer (round to nearest), which its low mantissa bits hold.
    const MAGIC: f32 = 12_582_912.0;
    let mut v = [0.0f32; LANES];
    let mut k = [0.0f32; LANES];
    for l in 0..LANES {
        v[l] = x[l].clamp(-87.0, 88.0);
        k[l] = v[l] * std::f32::consts::LOG2_E + MAGIC;
    }
    let mut r = [0.0f32; LANES];
    for l in 0..LANES {
        let n = k[l] - MAGIC;
        r[l] = (v[l] - n * C1) - n * C2;
    }
    let mut out = [0.0f32; LANES];
    for l in 0..LANES {
        let (r, z) = (r[l], r[l] * r[l]);
        let p = ((((P[0] * r + P[1]) * r + P[2]) * r + P[3]) * r + P[4]) * r + P[5];
        // 2^n from n's bits in k: n in [-126, 127] gives a normal exponent.
        let n = k[l].to_bits().wrapping_sub(MAGIC.to_bits()) as i32;
        let scale = f32::from_bits(((n + 127) << 23) as u32);
        out[l] = (p * z + r + 1.0) * scale;
    }
    F32x16(out)
}

/// Relative error bound of [`atan2_pos`] (Cephes `atanf`: 1.9e-7, plus the range reduction).
pub const ATAN_REL_ERROR: f32 = 4e-7;

/// atan2(y, x) for y >= 0, in [0, pi]: octant reduction and the Cephes `atanf` polynomial
/// (Moshier 1989), relative error < 4e-7 (tested against f64).
#[inline(always)]
pub fn atan2_pos<F: Real>(y: F, x: F) -> F {
    let zero = F::splat(0.0);
    let ax = x.abs();
    let low = y.le(ax);
    let (num, den) = (F::select(low, y, ax), F::select(low, ax, y));
    let z = F::select(den.gt(zero), num / den, zero);
    // atan on [0, 1]: around 1 through atan(z) = pi/4 + atan((z - 1) / (z + 1)).
    let high = z.gt(F::splat(0.414_213_57));
    let (base, z) = (F::select(high, F::splat(FRAC_PI_4), zero), F::select(high, (z - 1.0) / (z + 1.0), z));
    let z2 = z * z;
    let poly = (((z2 * 8.053_744_5e-2 - 1.387_768_6e-1) * z2 + 1.997_771_1e-1) * z2 - 3.333_295e-1) * z2 * z + z;
    let r = base + poly;
    let r = F::select(low, r, F::splat(FRAC_PI_2) - r);
    F::select(x.lt(zero), F::splat(PI) - r, r)
}

/// (sin x, cos x) for x in [0, pi]: Taylor polynomials of x/2 (terms to x^11 and x^12, whose
/// remainders at pi/2 are 6e-8 and 7e-9) and the double-angle formulas, which keep sin's
/// relative accuracy near 0. Errors < 3e-7, absolute, and relative for sin on [0, pi/2]
/// (tested); near pi, x itself carries more.
#[inline(always)]
pub fn sin_cos_0_pi<F: Real>(x: F) -> (F, F) {
    let one = F::splat(1.0);
    let h = x * 0.5;
    let h2 = h * h;
    let s = h * (one - h2 / 6.0 * (one - h2 / 20.0 * (one - h2 / 42.0 * (one - h2 / 72.0 * (one - h2 / 110.0)))));
    let c = one
        - h2 / 2.0 * (one - h2 / 12.0 * (one - h2 / 30.0 * (one - h2 / 56.0 * (one - h2 / 90.0 * (one - h2 / 132.0)))));
    // cos x from whichever of sin, cos (x/2) is under 1/sqrt 2, halving its error.
    (s * 2.0 * c, F::select(h.lt(F::splat(FRAC_PI_4)), one - s * 2.0 * s, c * 2.0 * c - 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lanes::{Level, at_level, level};

    /// Runs `f` over `xs` in blocks of LANES (the last padded with its first value) at every level
    /// the CPU has; returns the results per level (at least the baseline and `level()`).
    fn per_level(xs: &[[f32; 2]], f: impl Fn(&[f32; LANES], &[f32; LANES]) -> [f32; LANES]) -> Vec<Vec<f32>> {
        let levels: Vec<Vec<f32>> = Level::ALL
            .iter()
            .filter_map(|&lv| {
                at_level(
                    lv,
                    #[inline(always)]
                    || {
                        let mut out = Vec::with_capacity(xs.len());
                        for chunk in xs.chunks(LANES) {
                            let a = std::array::from_fn(|l| chunk.get(l).unwrap_or(&chunk[0])[0]);
                            let b = std::array::from_fn(|l| chunk.get(l).unwrap_or(&chunk[0])[1]);
                            out.extend_from_slice(&f(&a, &b)[..chunk.len()]);
                        }
                        out
                    },
                )
            })
            .collect();
        assert!(levels.len() > usize::from(level() != Level::Baseline));
        levels
    }

    #[test]
    fn exp_is_within_3_ulps_of_the_f64_exp_and_the_same_at_every_level() {
        // Dense over the range, the ends, the reduction's boundaries (n ln 2 / 2) and tiny arguments.
        let mut xs: Vec<f32> = (0..=200_000).map(|i| -87.0 + 175.0 * i as f32 / 200_000.0).collect();
        xs.extend((-250..=250).map(|n| n as f32 * std::f32::consts::LN_2 / 2.0).filter(|x| x.abs() <= 87.0));
        xs.extend([0.0, -0.0, 1e-30, -1e-30, 1e-7, -1e-7, 88.0, -87.0, f32::MIN_POSITIVE]);
        let pairs: Vec<[f32; 2]> = xs.iter().map(|&x| [x, 0.0]).collect();
        let levels = per_level(&pairs, |x, _| exp(F32x16(*x)).0);
        for got in &levels {
            assert_eq!(got, &levels[0], "the levels differ");
        }
        let worst = xs
            .iter()
            .zip(&levels[0])
            .map(|(&x, &g)| ((g as f64 - (x as f64).exp()) / (x as f64).exp()).abs())
            .fold(0.0f64, f64::max);
        assert!(worst < 2.5e-7, "exp: worst relative error {worst:e}");
        // Clamped, not overflowing or flushing to zero; NaN stays NaN.
        let ends = exp(F32x16(std::array::from_fn(|l| [1e3, -1e3, f32::NAN, 88.5][l % 4]))).0;
        assert_eq!(ends[0], exp(F32x16::splat(88.0))[0]);
        assert!(ends[0].is_finite() && ends[1] > 0.0 && ends[2].is_nan() && ends[3] == ends[0]);
    }

    #[test]
    fn atan2_pos_is_within_its_bound_of_f64() {
        let mut worst = 0.0f64;
        for i in 0..200_000 {
            // Angles over [0, pi], densest near the ends, at radii 1e-20 to 1e20.
            let t = i as f64 / 200_000.0;
            let theta = std::f64::consts::PI * t * t * (3.0 - 2.0 * t);
            let r = 10f64.powf(40.0 * ((i * 7919) % 1000) as f64 / 1000.0 - 20.0);
            let (y, x) = ((r * theta.sin()) as f32, (r * theta.cos()) as f32);
            let exact = (y as f64).atan2(x as f64);
            if exact > 0.0 {
                worst = worst.max((atan2_pos(y, x) as f64 - exact).abs() / exact);
            }
        }
        assert!(worst < ATAN_REL_ERROR as f64, "{worst}");
        // The lanes give the scalar bits at every level, at the octant boundaries and zeros too.
        let mut pairs: Vec<[f32; 2]> =
            (0..4096).map(|i| [(i as f32 * 0.37).sin().abs(), (i as f32 * 0.61).cos()]).collect();
        pairs.extend([[0.0, 0.0], [0.0, -0.0], [0.0, -1.0], [1.0, 0.0], [1.0, 1.0], [1.0, -1.0], [0.414_213_57, 1.0]]);
        for got in per_level(&pairs, |y, x| atan2_pos(F32x16(*y), F32x16(*x)).0) {
            let want: Vec<f32> = pairs.iter().map(|&[y, x]| atan2_pos(y, x)).collect();
            assert_eq!(
                got.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                want.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
            );
        }
    }

    #[test]
    fn sin_cos_0_pi_is_within_3e_7_of_f64() {
        for i in 0..=100_000 {
            let x = (PI * i as f32 / 100_000.0).min(PI);
            let (s, c) = sin_cos_0_pi(x);
            let (se, ce) = (x as f64).sin_cos();
            let sin_tol = if x <= std::f32::consts::FRAC_PI_2 { 3e-7 * se } else { 3e-7 };
            assert!((s as f64 - se).abs() <= sin_tol, "sin {x}");
            assert!((c as f64 - ce).abs() <= 3e-7, "cos {x}");
        }
        // Tiny arguments keep sin's relative accuracy.
        for x in [1e-30f32, 1e-10, 1e-5, 3e-3] {
            assert!(((sin_cos_0_pi(x).0 as f64) / (x as f64).sin() - 1.0).abs() < 3e-7);
        }
    }
}

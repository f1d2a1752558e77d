//! Elementary f32 functions over lane arrays, branch-free so that they vectorise (std's `exp`
//! and `atan2` are libm calls, one lane at a time). Each is written as one loop per step over
//! the lanes (see the parent module) and is accurate to a few ulps, not correctly rounded: kernels
//! that use them are tested against the scalar code they stand for.

use super::{F32x16, LANES};

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

/// atan2(y, x) per lane for y >= 0 (the angle of (x, y) from +x, in [0, pi]); 0 for y = x = 0.
/// Absolute error under 3e-7 and relative error under 3e-7 for small angles (the tests).
#[inline(always)]
pub fn atan2_upper(y: F32x16, x: F32x16) -> F32x16 {
    let (y, x) = (&y.0, &x.0);
    use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};
    // Cephes atanf (cephes/single/atanf.c): the ratio t = y / |x| reduced to |u| <= tan(pi/8) by
    // atan t = pi/4 + atan((t - 1) / (t + 1)) above tan(pi/8) and pi/2 - atan(1 / t) above
    // tan(3 pi/8), each formed as one quotient of y and |x| (one division per lane), then an
    // odd polynomial of degree 9.
    const TAN_3PI_8: f32 = 2.414_213_6;
    const TAN_PI_8: f32 = 0.414_213_57;
    const P: [f32; 4] = [8.053_744_5e-2, -1.387_768_5e-1, 1.997_771_1e-1, -3.333_295e-1];
    let mut u = [0.0f32; LANES];
    let mut base = [0.0f32; LANES];
    for l in 0..LANES {
        let (y, ax) = (y[l], x[l].abs());
        let big = y > TAN_3PI_8 * ax;
        let mid = y > TAN_PI_8 * ax;
        let num = if big {
            -ax
        } else if mid {
            y - ax
        } else {
            y
        };
        let den = if big {
            y
        } else if mid {
            y + ax
        } else {
            ax
        };
        base[l] = if big {
            FRAC_PI_2
        } else if mid {
            FRAC_PI_4
        } else {
            0.0
        };
        // y = x = 0: 0 / MIN_POSITIVE.
        u[l] = num / den.max(f32::MIN_POSITIVE);
    }
    let mut out = [0.0f32; LANES];
    for l in 0..LANES {
        let (u, z) = (u[l], u[l] * u[l]);
        let a = base[l] + ((((P[0] * z + P[1]) * z + P[2]) * z + P[3]) * z * u + u);
        out[l] = if x[l] < 0.0 { PI - a } else { a };
    }
    F32x16(out)
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
    fn atan2_upper_is_within_3e_7_of_the_f64_atan2_and_relatively_exact_near_zero() {
        // Angles over [0, pi], including each reduction boundary (pi/8, 3 pi/8 and their mirrors),
        // tiny angles from either axis, and radii from 1e-30 to 1e30.
        let mut pairs = Vec::new();
        for i in 0..=100_000 {
            let a = std::f64::consts::PI * i as f64 / 100_000.0;
            for r in [1.0, 1e-30, 3e7, 1e30] {
                pairs.push([(r * a.sin()).max(0.0) as f32, (r * a.cos()) as f32]);
            }
        }
        for k in 1..8 {
            let a = std::f64::consts::PI * k as f64 / 8.0;
            for e in [-1e-6, 0.0, 1e-6] {
                pairs.push([(a + e).sin() as f32, (a + e).cos() as f32]);
            }
        }
        for t in [1e-38, 1e-20, 1e-7, 3e-4, 1e-2] {
            pairs.extend([[t, 1.0], [t, -1.0], [1.0, t], [1.0, -t], [t, 0.5]]);
        }
        pairs.extend([[0.0, 0.0], [0.0, -0.0], [0.0, 1.0], [0.0, -1.0], [1.0, 0.0], [2.0, 0.0]]);
        let levels = per_level(&pairs, |y, x| atan2_upper(F32x16(*y), F32x16(*x)).0);
        for got in &levels {
            assert_eq!(got, &levels[0], "the levels differ");
        }
        let (mut abs, mut rel) = (0.0f64, 0.0f64);
        for (&[y, x], &g) in pairs.iter().zip(&levels[0]) {
            let want = (y as f64).atan2(x as f64);
            let want = if y == 0.0 && x == 0.0 { 0.0 } else { want };
            abs = abs.max((g as f64 - want).abs());
            if want > 0.0 && want < 0.5 {
                rel = rel.max((g as f64 - want).abs() / want);
            }
        }
        assert!(abs < 3e-7, "atan2: worst absolute error {abs:e}");
        assert!(rel < 3e-7, "atan2: worst relative error below 0.5 rad {rel:e}");
    }
}

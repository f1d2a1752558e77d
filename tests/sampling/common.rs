//! Test helpers: chi-square and finite-difference Jacobians.

use glam::{DVec2, DVec3, Vec2};

/// Pearson's statistic of `counts` against `probs` (summing to 1); zero-probability bins must be
/// empty (else +inf).
pub fn chi_square(counts: &[u64], probs: &[f64]) -> f64 {
    let n: u64 = counts.iter().sum();
    counts
        .iter()
        .zip(probs)
        .map(|(&c, &p)| {
            let e = p * n as f64;
            if e > 0.0 {
                (c as f64 - e).powi(2) / e
            } else if c > 0 {
                f64::INFINITY
            } else {
                0.0
            }
        })
        .sum()
}

/// Upper 1e-5 quantile of chi-square with `dof` degrees of freedom (Wilson-Hilferty 1931).
pub fn chi_square_critical(dof: usize) -> f64 {
    let k = dof as f64;
    let z = 4.265; // standard normal upper 1e-5 quantile
    k * (1.0 - 2.0 / (9.0 * k) + z * (2.0 / (9.0 * k)).sqrt()).powi(3)
}

/// Asserts the chi-square statistic is below the 1e-5 critical value; returns it.
pub fn assert_chi_square(what: &str, counts: &[u64], probs: &[f64]) -> f64 {
    let dof = probs.iter().filter(|&&p| p > 0.0).count() - 1;
    let (stat, crit) = (chi_square(counts, probs), chi_square_critical(dof));
    assert!(stat < crit, "{what}: chi-square {stat:.1} >= {crit:.1} (dof {dof})");
    stat
}

/// Mean and standard error of `n` values of `f` (Welford's running variance).
pub fn mean_and_error(n: usize, mut f: impl FnMut() -> f64) -> (f64, f64) {
    let (mut mean, mut m2) = (0.0, 0.0);
    for k in 1..=n {
        let v = f();
        let delta = v - mean;
        mean += delta / k as f64;
        m2 += delta * (v - mean);
    }
    (mean, (m2 / (n as f64 - 1.0) / n as f64).sqrt())
}

/// Step of the finite differences: a power of two, so u +- k h is exact on the test grids.
pub const H: f32 = 1.0 / 128.0;

/// Derivative of `f` at `u` along `axis`: 4th-order central differences at steps h and h/2,
/// Richardson-extrapolated to 6th order so maps like sqrt(u) near 0 stay within ~1e-5.
pub fn derivative<const K: usize>(f: &impl Fn(Vec2) -> [f64; K], u: Vec2, axis: usize) -> [f64; K] {
    let central = |h: f32| -> [f64; K] {
        let e = if axis == 0 { Vec2::X } else { Vec2::Y } * h;
        let (a, b, c, d) = (f(u + 2.0 * e), f(u + e), f(u - e), f(u - 2.0 * e));
        std::array::from_fn(|i| (-a[i] + 8.0 * b[i] - 8.0 * c[i] + d[i]) / (12.0 * h as f64))
    };
    let (coarse, fine) = (central(H), central(H / 2.0));
    std::array::from_fn(|i| (16.0 * fine[i] - coarse[i]) / 15.0)
}

/// |det| of the Jacobian of a map into the plane.
pub fn jacobian_2d(f: &impl Fn(Vec2) -> [f64; 2], u: Vec2) -> f64 {
    let (du, dv) = (DVec2::from(derivative(f, u, 0)), DVec2::from(derivative(f, u, 1)));
    du.perp_dot(dv).abs()
}

/// Area-scaling of a map onto the unit sphere: |dw/du0 × dw/du1| (steradians per unit u-area).
pub fn jacobian_sphere(f: &impl Fn(Vec2) -> [f64; 3], u: Vec2) -> f64 {
    let (du, dv) = (DVec3::from(derivative(f, u, 0)), DVec3::from(derivative(f, u, 1)));
    du.cross(dv).length()
}

/// Grid points in [lo, hi]^2 on multiples of 2^-10 (so u +- 2h is exact), `k` per axis.
pub fn u_grid(k: usize, lo: f32, hi: f32) -> Vec<Vec2> {
    let snap = |x: f32| (x * 1024.0).round() / 1024.0;
    let t = |i: usize| snap(lo + (hi - lo) * (i as f32 + 0.5) / k as f32);
    (0..k).flat_map(|i| (0..k).map(move |j| Vec2::new(t(i), t(j)))).collect()
}

/// Relative difference.
pub fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

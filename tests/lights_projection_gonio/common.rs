//! Shared helpers: stratified Monte Carlo with honest error bars, and the
//! pdf-agreement check.

use glam::{Vec2, Vec3};
use kelvin::geometry::Transform;
use kelvin::rng::SplitMix64;

pub const REPLICATES: usize = 64;
pub const SIDE: usize = 128;
pub const SAMPLES: usize = REPLICATES * SIDE * SIDE;

/// A Monte Carlo mean with its standard error.
#[derive(Clone, Copy, Debug)]
pub struct Estimate {
    pub mean: f64,
    pub sigma: f64,
}

/// The mean of `f` over the unit square from `REPLICATES` independent jittered `SIDE` x `SIDE` grids.
pub fn estimate(seed: u64, mut f: impl FnMut(Vec2) -> f64) -> Estimate {
    let mut rng = SplitMix64::new(seed);
    let means: Vec<f64> = (0..REPLICATES)
        .map(|_| {
            let mut sum = 0.0;
            for j in 0..SIDE {
                for i in 0..SIDE {
                    let u = Vec2::new((i as f32 + rng.f32()) / SIDE as f32, (j as f32 + rng.f32()) / SIDE as f32);
                    sum += f(u.min(Vec2::splat(1.0 - f32::EPSILON / 2.0)));
                }
            }
            sum / (SIDE * SIDE) as f64
        })
        .collect();
    let mean = means.iter().sum::<f64>() / REPLICATES as f64;
    let var = means.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / (REPLICATES - 1) as f64;
    Estimate { mean, sigma: (var / REPLICATES as f64).sqrt() }
}

/// Asserts `est` agrees with `expected` within 3 sigma (plus float rounding) and `rel_tol`; returns
/// the relative error.
pub fn check_mc(test: &str, what: &str, est: Estimate, expected: f64, rel_tol: f64) -> f64 {
    let err = (est.mean - expected).abs();
    let rel = err / expected.abs().max(1e-300);
    // Importance sampling can be exact (zero variance): then only float rounding is left.
    let sigmas = if est.sigma > 1e-9 * expected.abs() {
        format!("{:.2} sigma", err / est.sigma)
    } else {
        "zero variance".into()
    };
    eprintln!(
        "{test}: {what}: closed form {expected:.7e}, MC {:.7e} +- {:.2e} (rel err {rel:.2e}, {sigmas}, {SAMPLES} samples)",
        est.mean, est.sigma
    );
    assert!(est.mean.is_finite(), "{test}: {what}: estimate is not finite");
    assert!(err <= 3.0 * est.sigma + 1e-6 * expected.abs(), "{test}: {what}: off by {:.2} sigma", err / est.sigma);
    assert!(rel <= rel_tol, "{test}: {what}: relative error {rel:.2e} > {rel_tol:.0e}");
    rel
}

/// True when `uv` lies within `eps` texels of a texel edge of an `nu` x `nv` grid, where f32
/// rounding of a direction may decide the texel.
pub fn near_grid_edge(uv: Vec2, nu: usize, nv: usize, eps: f32) -> bool {
    let d = |x: f32, n: usize| {
        let t = x * n as f32;
        (t - t.round()).abs()
    };
    d(uv.x, nu) < eps || d(uv.y, nv) < eps
}

/// Draws `SAMPLES` directions and compares each sample's pdf with the pdf function: within 1e-4
/// everywhere but at texel edges (where f32 rounding of the direction may pick the neighbour),
/// which must be rare. Returns the largest relative difference off the edges.
pub fn check_pdf_agreement(
    test: &str,
    seed: u64,
    sample: impl Fn(Vec2) -> Option<(Vec3, f32)>,
    pdf: impl Fn(Vec3) -> f32,
    on_edge: impl Fn(Vec3) -> bool,
) -> f64 {
    let mut rng = SplitMix64::new(seed);
    let (mut drawn, mut worst, mut edge_mismatches) = (0usize, 0.0f64, 0usize);
    for _ in 0..SAMPLES {
        let u = Vec2::new(rng.f32(), rng.f32());
        let Some((w, p)) = sample(u) else { continue };
        drawn += 1;
        assert!((w.length() - 1.0).abs() < 1e-5 && p.is_finite() && p > 0.0, "{test}: bad sample {w} pdf {p}");
        let q = pdf(w);
        let rel = ((p - q).abs() / p) as f64;
        if rel > 1e-4 && on_edge(w) {
            edge_mismatches += 1;
        } else {
            assert!(rel <= 1e-4, "{test}: sample pdf {p} but pdf function {q} at {w} (u = {u})");
            worst = worst.max(rel);
        }
    }
    eprintln!(
        "{test}: pdf of sample vs pdf function: max rel diff {worst:.2e} over {drawn} samples; \
         {edge_mismatches} differ at texel edges"
    );
    assert!(drawn > SAMPLES / 2, "{test}: only {drawn} samples drawn");
    assert!(edge_mismatches as f64 <= 1e-4 * drawn as f64, "{test}: {edge_mismatches} mismatches at texel edges");
    worst
}

/// Relative tolerance of uniform-sphere estimates: they also pass 3 sigma, but a frustum with
/// hundreds of sharp texel edges leaves ~1e-3 of noise at 2^20 samples.
pub const UNIFORM_TOL: f64 = 1e-2;

/// A light position and an oblique aim, so frames are exercised.
pub fn tilted_transform() -> Transform {
    Transform::from_translation(Vec3::new(1.0, 2.0, -0.5)).looking_to(Vec3::new(0.3, -1.0, 0.2), Vec3::Y)
}

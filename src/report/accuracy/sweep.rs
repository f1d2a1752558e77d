//! Rendering a knob's settings and measuring them against a reference.

use glam::Vec3;

use super::knobs::{Config, Knob};
use super::metrics::{max_error, patch_de00, rel_mse};
use super::reference::Reference;
use super::scenes::BuiltScene;
use super::{Against, Budget, Row};
use crate::render::renderer::render;
use crate::shading::ShadingBatch;

/// The renders of one configuration: images per seed and the fastest time.
pub struct Renders {
    pub config: Config,
    pub images: Vec<Vec<Vec3>>,
    pub seconds: f64,
    pub samples: u64,
}

/// Renders every configuration `budget.reps` times (seeds 1, 2, ...), one round over all of them
/// per seed, after one untimed 1-spp warm-up render each (caches, threads). Before each timed
/// render an untimed update rebuilds whatever the configuration needs (env tables, sampler).
pub fn render_knob(scene: &mut BuiltScene, configs: &[Config], budget: &Budget) -> Vec<Renders> {
    let (w, h) = (budget.width, budget.height);
    let mut out: Vec<Renders> = configs
        .iter()
        .map(|c| Renders { config: *c, images: Vec::new(), seconds: f64::INFINITY, samples: 0 })
        .collect();
    for c in configs {
        c.apply(&mut scene.world, 1);
        render(&mut scene.world, &mut scene.schedule, &Config { spp: 1, ..*c }.render_options(w, h), |_| {});
    }
    for rep in 0..budget.reps.max(1) {
        for (c, r) in configs.iter().zip(out.iter_mut()) {
            c.apply(&mut scene.world, 1 + rep as u64);
            scene.world.resource_mut::<ShadingBatch>().clear();
            scene.schedule.run(&mut scene.world);
            let (film, stats) = render(&mut scene.world, &mut scene.schedule, &c.render_options(w, h), |_| {});
            r.images.push(film.pixels());
            if stats.seconds < r.seconds {
                (r.seconds, r.samples) = (stats.seconds, stats.camera_samples);
            }
        }
    }
    out
}

/// Squared bias of the renders (relative-MSE units) and its standard error; see [`Row::bias2`].
/// Per pixel, t = (n |mean - ref|^2 - mean_k |x_k - ref|^2) / (n - 1) estimates bias^2 without
/// the variance; the standard error comes from the spread of t over pixels (conservative).
fn bias2(images: &[Vec<Vec3>], reference: &[Vec3]) -> (f64, f64) {
    let n = images.len();
    if n < 2 {
        return (f64::NAN, f64::NAN);
    }
    let nf = n as f64;
    let norm: f64 = reference.iter().map(|r| r.as_dvec3().length_squared()).sum();
    let t: Vec<f64> = (0..reference.len())
        .map(|p| {
            let r = reference[p].as_dvec3();
            let mean = images.iter().map(|im| im[p].as_dvec3()).sum::<glam::DVec3>() / nf;
            let spread = images.iter().map(|im| (im[p].as_dvec3() - r).length_squared()).sum::<f64>() / nf;
            (nf * (mean - r).length_squared() - spread) / (nf - 1.0)
        })
        .collect();
    let m = t.len() as f64;
    let sum: f64 = t.iter().sum();
    let var = t.iter().map(|v| (v - sum / m).powi(2)).sum::<f64>() / (m - 1.0).max(1.0);
    let norm = if norm > 0.0 { norm } else { 1.0 };
    (sum / norm, (m * var).sqrt() / norm)
}

/// The errors of `r` against `reference` as a row (ratios and Pareto filled in by `finish_rows`).
pub fn measure(
    knob: Knob,
    setting: String,
    r: &Renders,
    reference: &Reference,
    against: Against,
    scene: &BuiltScene,
    budget: &Budget,
) -> Row {
    let n = r.images.len().max(1) as f64;
    let mean = |f: &dyn Fn(&[Vec3]) -> f64| r.images.iter().map(|im| f(im)).sum::<f64>() / n;
    let (bias2, bias2_se) = bias2(&r.images, &reference.pixels);
    let de00 = scene.checker.as_ref().map(|c| {
        let (w, h) = (budget.width, budget.height);
        let des: Vec<(f64, f64)> = r.images.iter().map(|im| patch_de00(im, &reference.pixels, c, w, h)).collect();
        (des.iter().map(|d| d.0).sum::<f64>() / n, des.iter().map(|d| d.1).sum::<f64>() / n)
    });
    Row {
        knob,
        setting,
        config: r.config,
        seconds: r.seconds,
        norm_seconds: r.seconds,
        samples_per_s: r.samples as f64 / r.seconds.max(1e-9),
        rel_mse: mean(&|im| rel_mse(im, &reference.pixels)),
        max_err: mean(&|im| max_error(im, &reference.pixels)),
        bias2,
        bias2_se,
        de00,
        against,
        baseline: false,
        time_ratio: 1.0,
        error_ratio: 1.0,
        efficiency: 1.0,
        pareto: false,
    }
}

/// Fills each row's ratios against its knob's baseline row and its normalised time, and marks
/// the Pareto front.
pub fn finish_rows(rows: &mut [Row], base: &Config) {
    for knob in Knob::ALL {
        let Some(b) = rows.iter().find(|r| r.knob == knob && r.config == *base).cloned() else { continue };
        for r in rows.iter_mut().filter(|r| r.knob == knob) {
            r.baseline = r.config == *base;
            r.time_ratio = r.seconds / b.seconds.max(1e-12);
            r.error_ratio = r.rel_mse / b.rel_mse.max(1e-300);
            r.efficiency = (b.rel_mse * b.seconds) / (r.rel_mse * r.seconds).max(1e-300);
        }
    }
    let t0 = rows.iter().find(|r| r.knob == Knob::Spp && r.baseline).map(|r| r.seconds);
    for r in rows.iter_mut() {
        r.norm_seconds = t0.map_or(r.seconds, |t| r.time_ratio * t);
    }
    let main: Vec<usize> = (0..rows.len()).filter(|&i| rows[i].against == Against::Main).collect();
    for &i in &main {
        let dominated = main.iter().any(|&j| {
            let (a, b) = (&rows[j], &rows[i]);
            j != i
                && a.seconds <= b.seconds
                && a.rel_mse <= b.rel_mse
                && (a.seconds < b.seconds || a.rel_mse < b.rel_mse)
        });
        rows[i].pareto = !dominated;
    }
}

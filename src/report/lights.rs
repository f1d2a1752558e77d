//! The many-lights report: for each light count N on the scaling scene (and once on the
//! emissive-panel room), each sampler's time per sample and relative RMSE at equal time, and the
//! frame update time when 1% or 10% of the lights move against a full rebuild.
//!
//! **Error.** The quantity is unshadowed photometric irradiance (lx) at fixed ground points, so
//! the exact answer is the sum over all lights. A one-light-per-sample estimate f/pmf has
//! relative variance V = (sum_l f_l^2 / pmf_l) / E^2 - 1 at each point; it is computed exactly
//! (every light's pmf in one pass) and reported as the relative RMSE of one sample,
//! sqrt(mean over points of V). A measured RMSE with `samples` samples per point is printed next
//! to it as a check. **Equal time** multiplies by sqrt(t / t_uniform), t the measured time per
//! sample (choose a light + Sample_Li + the cosine), i.e. the error each sampler reaches in the
//! time uniform sampling takes for one sample.

use std::path::{Path, PathBuf};
use std::time::Instant;

use bevy_ecs::prelude::*;
use glam::Vec3;
use rayon::prelude::*;

use super::plot::{PlotError, PlotSpec, Series, line_plot};
use crate::geometry::{SceneBvh, SurfacePoint};
use crate::light::{ColorQuery, LightId, LightKind, LightSampleContext, LightTable};
use crate::light_sampler::{BvhSampler, BvhUpdate, LightSampler, PowerSampler};
use crate::rng::SplitMix64;
use crate::scenes::{scene_rng, spawn_emissive_panel_room, spawn_scaling_scene};
use crate::shading::{LightSamplerKind, Settings};
use crate::systems::LightingPlugin;

/// Timing runs per sampler; the fastest counts.
const TIMING_RUNS: usize = 5;

/// The samplers compared, in table order.
pub const KINDS: [LightSamplerKind; 3] = [LightSamplerKind::Uniform, LightSamplerKind::Power, LightSamplerKind::Bvh];

/// What to measure.
#[derive(Clone, Debug)]
pub struct LightBenchConfig {
    /// Light counts of the scaling scene.
    pub counts: Vec<usize>,
    /// Ground points where irradiance is estimated.
    pub points: usize,
    /// Samples per point for the timing and the measured RMSE.
    pub samples: usize,
    /// Frames timed for each update (the fastest counts).
    pub frames: usize,
    /// How far a moving light moves per frame, m (per horizontal axis, at most).
    pub move_step: f32,
    /// Tiles per side of the emissive panel (2 tiles^2 triangles); 0 skips the panel room.
    pub panel_tiles: usize,
    /// Seed of the scenes, the ground points and the moves.
    pub seed: u64,
}

impl Default for LightBenchConfig {
    fn default() -> Self {
        Self {
            counts: vec![1, 10, 100, 1_000, 10_000, 100_000, 1_000_000],
            points: 128,
            samples: 512,
            frames: 10,
            // A car at ~15 m/s seen at 60 frames per second.
            move_step: 0.25,
            panel_tiles: 64,
            seed: 1,
        }
    }
}

/// One sampler on one scene.
#[derive(Clone, Debug, Default)]
pub struct SamplerFigures {
    /// Build time, ms.
    pub build_ms: f64,
    /// Time per sample (choose + Sample_Li + cosine), ns, one thread.
    pub ns_per_sample: f64,
    /// Relative RMSE of a one-sample estimate, from the exact variance.
    pub rel_rmse: f64,
    /// `rel_rmse` at the time one uniform sample takes.
    pub rel_rmse_equal_time: f64,
    /// Time per sample including its shadow ray through the scene BVH, ns, one thread.
    pub ns_with_shadow_ray: f64,
    /// `rel_rmse` at the time one uniform sample with its shadow ray takes.
    pub rel_rmse_equal_time_with_ray: f64,
    /// Measured relative RMSE with `samples` samples per point.
    pub measured_rel_rmse: f64,
    /// Fraction of points where a light that contributes has pmf 0 (must be 0: unbiased).
    pub biased_points: f64,
}

/// Update times for one light count, ms (the fastest of the timed frames).
#[derive(Clone, Debug, Default)]
pub struct UpdateFigures {
    /// Power sampler update after 1% of the lights moved.
    pub power_move_1pct_ms: f64,
    /// Power sampler built from scratch.
    pub power_rebuild_ms: f64,
    /// Light BVH update (refit, or rebuild when the cost ratio calls for it) after 1% moved.
    pub bvh_refit_1pct_ms: f64,
    /// Light BVH update after 10% of the lights moved.
    pub bvh_refit_10pct_ms: f64,
    /// Light BVH built from scratch.
    pub bvh_rebuild_ms: f64,
    /// Rebuilds the cost-ratio test triggered during the moving frames.
    pub bvh_rebuilds: usize,
    /// Cost ratio after the last moving frame.
    pub cost_ratio: f32,
    /// Nodes the last 1% refit recomputed (leaves included), of `2 N - 1`.
    pub refit_nodes_1pct: usize,
}

/// All figures for one scene.
#[derive(Clone, Debug, Default)]
pub struct LightBenchRow {
    /// `"scaling"` or `"panel"`.
    pub scene: String,
    /// Number of lights (emitting triangles in the panel room).
    pub n: usize,
    /// Spawning and syncing the scene through the ECS, ms.
    pub scene_ms: f64,
    /// Depth of the light BVH's deepest leaf.
    pub bvh_depth: usize,
    /// One entry per sampler, in [`KINDS`] order.
    pub samplers: Vec<SamplerFigures>,
    /// Update times; scaling scene only.
    pub update: Option<UpdateFigures>,
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// The fastest of several timings: other processes on the machine only ever add time.
fn fastest(v: Vec<f64>) -> f64 {
    v.into_iter().reduce(f64::min).unwrap_or(0.0)
}

/// Unshadowed photometric irradiance (lx) at `ctx` from light `id`: Sample_Li's luminance Y times
/// the receiver cosine (exact for delta lights).
#[inline]
pub fn irradiance(table: &LightTable, id: LightId, ctx: &LightSampleContext) -> f64 {
    table
        .sample_li(id, ctx, glam::Vec2::splat(0.5), ColorQuery::Rgb)
        .map_or(0.0, |ls| (luminance(&ls.radiance) * ls.wi.dot(ctx.n).max(0.0)) as f64)
}

/// Luminance Y of an RGB query's radiance (its channels are linear sRGB).
fn luminance(radiance: &crate::spectrum::SampledSpectrum) -> f32 {
    glam::Vec3::from_slice(&radiance.0[..3]).dot(crate::scene::image::LUMINANCE_WEIGHTS)
}

/// A scene synced through the ECS: its light table (change flags cleared) and scene BVH.
pub struct SyncedScene {
    /// The scene's lights.
    pub table: LightTable,
    /// The scene's geometry, for shadow rays.
    pub bvh: SceneBvh,
    /// Spawning and syncing time, ms.
    pub ms: f64,
}

/// Spawns a scene through the ECS and keeps its light table and scene BVH.
fn synced_scene(spawn: impl FnOnce(&mut World)) -> SyncedScene {
    let t = Instant::now();
    let mut world = World::new();
    let mut schedule = Schedule::default();
    world.insert_resource(Settings { light_sampler: LightSamplerKind::Uniform, ..Default::default() });
    LightingPlugin::build(&mut world, &mut schedule);
    spawn(&mut world);
    schedule.run(&mut world);
    let mut table = world.remove_resource::<LightTable>().unwrap_or_default();
    table.clear_change_flags();
    let bvh = world.remove_resource::<SceneBvh>().unwrap_or_default();
    SyncedScene { table, bvh, ms: ms(t) }
}

/// The scaling scene of `n` lights synced into a light table (change flags cleared), with
/// `points` ground points to shade.
pub fn scaling_scene_table(n: usize, seed: u64, points: usize) -> (LightTable, Vec<LightSampleContext>) {
    let mut scene = None;
    let synced = synced_scene(|w| scene = Some(spawn_scaling_scene(w, n, seed)));
    (synced.table, scene.expect("spawned").ground_points(points, seed))
}

/// The exact irradiance at `ctx`, and the exact relative variance of each sampler's one-sample
/// estimate there with whether some contributing light has pmf 0.
fn exact_relative_variance(
    samplers: &[LightSampler],
    table: &LightTable,
    ctx: &LightSampleContext,
) -> (f64, Vec<(f64, bool)>) {
    let exact: f64 = table.ids().map(|id| irradiance(table, id, ctx)).sum();
    let variances = samplers
        .iter()
        .map(|s| {
            let (mut second, mut biased) = (0.0, false);
            s.for_each_pmf(ctx, |id, pmf| {
                let f = irradiance(table, id, ctx);
                if f > 0.0 {
                    if pmf > 0.0 { second += f * f / pmf as f64 } else { biased = true }
                }
            });
            if exact > 0.0 { ((second / (exact * exact) - 1.0).max(0.0), biased) } else { (0.0, false) }
        })
        .collect();
    (exact, variances)
}

/// The mean over `points` of the exact relative variance of `sampler`'s one-sample estimate.
pub fn mean_relative_variance(sampler: &LightSampler, table: &LightTable, points: &[LightSampleContext]) -> f64 {
    let per_point: Vec<f64> = points
        .par_iter()
        .map(|ctx| exact_relative_variance(std::slice::from_ref(sampler), table, ctx).1[0].0)
        .collect();
    per_point.iter().sum::<f64>() / points.len().max(1) as f64
}

/// Time per sample (ns) and measured relative RMSE with `samples` samples per point. With
/// `shadows`, each sample also traces its shadow ray (the light system's per-sample cost; the
/// answer is ignored, the estimate stays unshadowed).
fn time_and_measure(
    s: &LightSampler,
    table: &LightTable,
    points: &[LightSampleContext],
    exact: &[f64],
    samples: usize,
    seed: u64,
    shadows: Option<&SceneBvh>,
) -> (f64, f64) {
    let mut rng = scene_rng(seed);
    let us: Vec<f32> = (0..samples).map(|_| rng.f32()).collect();
    let t = Instant::now();
    let mut estimates = Vec::with_capacity(points.len());
    for (k, ctx) in points.iter().enumerate() {
        let mut sum = 0.0;
        for &u in &us {
            // Decorrelate points with a per-point rotation of the shared numbers.
            let u = (u + k as f32 * 0.618_034) % 1.0;
            let Some((id, pmf)) = s.sample(ctx, u) else { continue };
            let Some(ls) = table.sample_li(id, ctx, glam::Vec2::splat(0.5), ColorQuery::Rgb) else { continue };
            if let Some(bvh) = shadows {
                let ray = SurfacePoint::from_point(ctx.p, ctx.n).spawn_ray_to_point(ls.p_light);
                std::hint::black_box(bvh.occluded(&ray));
            }
            sum += (luminance(&ls.radiance) * ls.wi.dot(ctx.n).max(0.0)) as f64 / pmf as f64;
        }
        estimates.push(sum / samples as f64);
    }
    let ns = t.elapsed().as_secs_f64() * 1e9 / (points.len() * samples) as f64;
    let (mut sq, mut count) = (0.0, 0);
    for (&e, &x) in estimates.iter().zip(exact) {
        if x > 0.0 {
            sq += ((e - x) / x).powi(2);
            count += 1;
        }
    }
    (ns, if count > 0 { (sq / count as f64).sqrt() } else { 0.0 })
}

fn sampler_figures(
    table: &LightTable,
    bvh: &SceneBvh,
    points: &[LightSampleContext],
    cfg: &LightBenchConfig,
) -> (Vec<SamplerFigures>, usize) {
    let mut figures = Vec::new();
    let mut samplers = Vec::new();
    for kind in KINDS {
        let t = Instant::now();
        samplers.push(LightSampler::build(kind, table));
        figures.push(SamplerFigures { build_ms: ms(t), ..Default::default() });
    }
    let depth = match &samplers[2] {
        LightSampler::Bvh(b) => b.depth(),
        _ => 0,
    };
    let (exact, per_point): (Vec<f64>, Vec<Vec<(f64, bool)>>) =
        points.par_iter().map(|ctx| exact_relative_variance(&samplers, table, ctx)).unzip();
    let lit = exact.iter().filter(|&&e| e > 0.0).count().max(1) as f64;
    for (k, f) in figures.iter_mut().enumerate() {
        let mean_var: f64 = per_point.iter().map(|v| v[k].0).sum::<f64>() / lit;
        f.rel_rmse = mean_var.sqrt();
        f.biased_points = per_point.iter().filter(|v| v[k].1).count() as f64 / points.len() as f64;
        (f.ns_per_sample, f.ns_with_shadow_ray) = (f64::INFINITY, f64::INFINITY);
    }
    // The fastest of a few interleaved runs: other processes only ever add time.
    for _ in 0..TIMING_RUNS {
        for (k, f) in figures.iter_mut().enumerate() {
            let seed = cfg.seed + k as u64;
            let (ns, rmse) = time_and_measure(&samplers[k], table, points, &exact, cfg.samples, seed, None);
            (f.ns_per_sample, f.measured_rel_rmse) = (f.ns_per_sample.min(ns), rmse);
            let (ns, _) = time_and_measure(&samplers[k], table, points, &exact, cfg.samples, seed, Some(bvh));
            f.ns_with_shadow_ray = f.ns_with_shadow_ray.min(ns);
        }
    }
    let (t_ref, t_ref_ray) = (figures[0].ns_per_sample, figures[0].ns_with_shadow_ray);
    for f in &mut figures {
        f.rel_rmse_equal_time = f.rel_rmse * (f.ns_per_sample / t_ref).sqrt();
        f.rel_rmse_equal_time_with_ray = f.rel_rmse * (f.ns_with_shadow_ray / t_ref_ray).sqrt();
    }
    (figures, depth)
}

/// Moves light `id` by `delta` in place (point and spot lights). Returns false for other kinds.
pub fn move_light(table: &mut LightTable, id: LightId, delta: Vec3) -> bool {
    let i = id.row as usize;
    let owner = table.owner(id);
    match id.kind {
        LightKind::Point => {
            let mut row = table.points.get(i);
            row.position += delta;
            let shadows = table.points.casts_shadows[i];
            table.upsert_point(owner, row, shadows, false);
        }
        LightKind::Spot => {
            let mut row = table.spots.get(i);
            row.position += delta;
            let shadows = table.spots.casts_shadows[i];
            table.upsert_spot(owner, row, shadows, false);
        }
        LightKind::Area
        | LightKind::Projection
        | LightKind::Goniometric
        | LightKind::Distant
        | LightKind::UniformInfinite
        | LightKind::ImageInfinite
        | LightKind::SunSky => return false,
    }
    true
}

/// Moves `fraction` of the lights (chosen at random) by up to `step` metres along each
/// horizontal axis (and a fifth of it vertically).
pub fn move_fraction(table: &mut LightTable, fraction: f64, step: f32, rng: &mut SplitMix64) {
    let n = table.len();
    let k = ((n as f64 * fraction).round() as usize).max(1);
    let ids: Vec<LightId> = table.ids().collect();
    for _ in 0..k {
        let id = ids[rng.below(n)];
        let delta = step * Vec3::new(rng.range(-1.0, 1.0), rng.range(-0.2, 0.2), rng.range(-1.0, 1.0));
        move_light(table, id, delta);
    }
}

fn update_figures(table: &mut LightTable, frames: usize, step: f32, seed: u64) -> UpdateFigures {
    let mut rng = scene_rng(seed);
    let mut out = UpdateFigures::default();
    let (mut power, mut bvh) = (PowerSampler::build(table), BvhSampler::build(table));
    let mut times = |fraction: f64, bvh_only: bool, out: &mut UpdateFigures| {
        let (mut tp, mut tb) = (Vec::new(), Vec::new());
        for _ in 0..frames {
            move_fraction(table, fraction, step, &mut rng);
            if !bvh_only {
                let t = Instant::now();
                power.update(table);
                tp.push(ms(t));
            }
            let t = Instant::now();
            bvh.update(table);
            tb.push(ms(t));
            match bvh.last_update {
                BvhUpdate::Rebuilt => out.bvh_rebuilds += 1,
                BvhUpdate::Refit { cost_ratio, nodes } => {
                    out.cost_ratio = cost_ratio;
                    if fraction == 0.01 {
                        out.refit_nodes_1pct = nodes;
                    }
                }
                BvhUpdate::UpToDate => {}
            }
            table.clear_change_flags();
        }
        (fastest(tp), fastest(tb))
    };
    (out.power_move_1pct_ms, out.bvh_refit_1pct_ms) = times(0.01, false, &mut out);
    out.bvh_refit_10pct_ms = times(0.10, true, &mut out).1;
    let builds = frames.clamp(1, 3);
    out.power_rebuild_ms = fastest((0..builds).map(|_| ms_of(|| drop(PowerSampler::build(table)))).collect());
    out.bvh_rebuild_ms = fastest((0..builds).map(|_| ms_of(|| drop(BvhSampler::build(table)))).collect());
    out
}

fn ms_of(f: impl FnOnce()) -> f64 {
    let t = Instant::now();
    f();
    ms(t)
}

/// Runs the benchmark, calling `progress` with a line per step.
pub fn run_light_bench(cfg: &LightBenchConfig, mut progress: impl FnMut(&str)) -> Vec<LightBenchRow> {
    let mut rows = Vec::new();
    for &n in &cfg.counts {
        progress(&format!("scaling scene, N = {n}: spawning and syncing"));
        let mut scene = None;
        let SyncedScene { mut table, bvh, ms: scene_ms } =
            synced_scene(|w| scene = Some(spawn_scaling_scene(w, n, cfg.seed)));
        let points = scene.expect("spawned").ground_points(cfg.points, cfg.seed);
        progress(&format!("scaling scene, N = {n}: samplers"));
        let (samplers, bvh_depth) = sampler_figures(&table, &bvh, &points, cfg);
        progress(&format!("scaling scene, N = {n}: updates"));
        let update = Some(update_figures(&mut table, cfg.frames, cfg.move_step, cfg.seed));
        rows.push(LightBenchRow { scene: "scaling".into(), n, scene_ms, bvh_depth, samplers, update });
    }
    if cfg.panel_tiles > 0 {
        progress(&format!("emissive panel room, {} triangles", 2 * cfg.panel_tiles * cfg.panel_tiles));
        let mut scene = None;
        let SyncedScene { table, bvh, ms: scene_ms } =
            synced_scene(|w| scene = Some(spawn_emissive_panel_room(w, cfg.panel_tiles, cfg.seed)));
        let points = scene.expect("spawned").floor_points(cfg.points, cfg.seed);
        let (samplers, bvh_depth) = sampler_figures(&table, &bvh, &points, cfg);
        rows.push(LightBenchRow { scene: "panel".into(), n: table.len(), scene_ms, bvh_depth, samplers, update: None });
    }
    rows
}

/// The tables, as text.
pub fn format_tables(rows: &[LightBenchRow], samples: usize, move_step: f32) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(s, "Sampling: unshadowed illuminance at ground points. rmse = relative RMSE of one sample (exact");
    let _ = writeln!(s, "variance); eqT = rmse x sqrt(t / t_uniform), t = time per sample: choose + Sample_Li (+ its");
    let _ = writeln!(
        s,
        "shadow ray through the scene BVH, '+ray'); measured = relative RMSE at {samples} samples per point."
    );
    let _ = writeln!(
        s,
        "{:<8} {:>8} {:>5} | {:>7} {:>7} {:>7} | {:>8} {:>8} {:>8} | {:>8} {:>8} {:>8} | {:>7} {:>7} {:>7} | {:>8} {:>8} {:>8} | {:>7} {:>7} | {:>8}",
        "scene",
        "N",
        "depth",
        "ns unif",
        "ns pow",
        "ns bvh",
        "rmse uni",
        "rmse pow",
        "rmse bvh",
        "eqT uni",
        "eqT pow",
        "eqT bvh",
        "+ray un",
        "+ray pw",
        "+ray bv",
        "eqT+r un",
        "eqT+r pw",
        "eqT+r bv",
        "un/bvh",
        "+ray",
        "meas bvh"
    );
    for r in rows {
        let f = &r.samplers;
        let ratio = |a: f64, b: f64| a / b.max(f64::MIN_POSITIVE);
        let _ = writeln!(
            s,
            "{:<8} {:>8} {:>5} | {:>7.1} {:>7.1} {:>7.1} | {:>8.3} {:>8.3} {:>8.3} | {:>8.3} {:>8.3} {:>8.3} | {:>7.1} {:>7.1} {:>7.1} | {:>8.3} {:>8.3} {:>8.3} | {:>7.1} {:>7.1} | {:>8.2e}",
            r.scene,
            r.n,
            r.bvh_depth,
            f[0].ns_per_sample,
            f[1].ns_per_sample,
            f[2].ns_per_sample,
            f[0].rel_rmse,
            f[1].rel_rmse,
            f[2].rel_rmse,
            f[0].rel_rmse_equal_time,
            f[1].rel_rmse_equal_time,
            f[2].rel_rmse_equal_time,
            f[0].ns_with_shadow_ray,
            f[1].ns_with_shadow_ray,
            f[2].ns_with_shadow_ray,
            f[0].rel_rmse_equal_time_with_ray,
            f[1].rel_rmse_equal_time_with_ray,
            f[2].rel_rmse_equal_time_with_ray,
            ratio(f[0].rel_rmse_equal_time, f[2].rel_rmse_equal_time),
            ratio(f[0].rel_rmse_equal_time_with_ray, f[2].rel_rmse_equal_time_with_ray),
            f[2].measured_rel_rmse,
        );
        for (k, x) in f.iter().enumerate() {
            if x.biased_points > 0.0 {
                let _ = writeln!(
                    s,
                    "  WARNING: {:?} gives pmf 0 to a contributing light at {:.1}% of points",
                    KINDS[k],
                    100.0 * x.biased_points
                );
            }
        }
    }
    let _ = writeln!(
        s,
        "\nUpdates (ms, fastest frame; each moving light moves by up to {move_step} m per axis; new = build from scratch;"
    );
    let _ = writeln!(s, "nodes = nodes the 1% refit recomputed; scene = spawn + ECS sync)");
    let _ = writeln!(
        s,
        "{:>8} | {:>9} | {:>9} {:>9} | {:>9} {:>9} {:>9} | {:>10} {:>8} {:>8} {:>6}",
        "N", "scene", "power 1%", "power new", "bvh 1%", "bvh 10%", "bvh new", "new / 1%", "nodes", "rebuilds", "cost"
    );
    for r in rows {
        let Some(u) = &r.update else { continue };
        let _ = writeln!(
            s,
            "{:>8} | {:>9.1} | {:>9.4} {:>9.3} | {:>9.4} {:>9.4} {:>9.3} | {:>10.1} {:>8} {:>8} {:>6.3}",
            r.n,
            r.scene_ms,
            u.power_move_1pct_ms,
            u.power_rebuild_ms,
            u.bvh_refit_1pct_ms,
            u.bvh_refit_10pct_ms,
            u.bvh_rebuild_ms,
            u.bvh_rebuild_ms / u.bvh_refit_1pct_ms.max(1e-9),
            u.refit_nodes_1pct,
            u.bvh_rebuilds,
            u.cost_ratio,
        );
    }
    s
}

/// Writes the four plots (log10 axes) into `dir`; returns their paths.
pub fn write_plots(rows: &[LightBenchRow], dir: &Path) -> Result<Vec<PathBuf>, PlotError> {
    let scaling: Vec<&LightBenchRow> = rows.iter().filter(|r| r.scene == "scaling").collect();
    let log = |x: f64| x.max(1e-12).log10();
    let per_sampler = |value: fn(&SamplerFigures) -> f64| -> Vec<Series> {
        KINDS
            .iter()
            .enumerate()
            .map(|(k, kind)| Series {
                name: format!("{kind:?}"),
                points: scaling.iter().map(|r| (log(r.n as f64), log(value(&r.samplers[k])))).collect(),
            })
            .collect()
    };
    let mut written = Vec::new();
    let mut plot = |name: &str, title: &str, y: &str, series: &[Series]| -> Result<(), PlotError> {
        let path = dir.join(name);
        line_plot(&path, &PlotSpec { title, x_label: "log10 N (lights)", y_label: y, equal_aspect: false }, series)?;
        written.push(path);
        Ok(())
    };
    plot("lights_time_per_sample.svg", "Time per light sample", "log10 ns", &per_sampler(|f| f.ns_per_sample))?;
    plot(
        "lights_rmse_equal_time.svg",
        "Relative RMSE at equal time (uniform's time per sample)",
        "log10 relative RMSE",
        &per_sampler(|f| f.rel_rmse_equal_time),
    )?;
    plot(
        "lights_rmse_equal_time_with_shadow_ray.svg",
        "Relative RMSE at equal time, each sample with its shadow ray",
        "log10 relative RMSE",
        &per_sampler(|f| f.rel_rmse_equal_time_with_ray),
    )?;
    type Curve = (&'static str, fn(&UpdateFigures) -> f64);
    let updates: [Curve; 4] = [
        ("BVH refit, 1% move", |u| u.bvh_refit_1pct_ms),
        ("BVH refit, 10% move", |u| u.bvh_refit_10pct_ms),
        ("BVH full rebuild", |u| u.bvh_rebuild_ms),
        ("power: alias rebuild", |u| u.power_rebuild_ms),
    ];
    let series: Vec<Series> = updates
        .iter()
        .map(|(name, value)| Series {
            name: name.to_string(),
            points: scaling
                .iter()
                .filter_map(|r| r.update.as_ref().map(|u| (log(r.n as f64), log(value(u)))))
                .collect(),
        })
        .collect();
    plot("lights_update.svg", "Sampler update per frame", "log10 ms", &series)?;
    Ok(written)
}

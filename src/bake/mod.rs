//! Baked light for game engines: lightmaps on a mesh's second uv set (`kelvin bake lightmaps`).
//!
//! [`bake_lightmaps`] takes a world loaded as `kelvin render` loads one (a [`LoadedJob`]) and bakes,
//! for each placed glTF mesh with TEXCOORD_1, a square lightmap. A texel holds what a game engine
//! multiplies by a surface's diffuse colour (Bevy: `lightmap * diffuse_color * lightmap_exposure`):
//! the irradiance there over pi, i.e. the radiance a white Lambertian surface would reflect, in
//! linear sRGB and kelvin's photometric units (nit). It is estimated by paths that start at points
//! spread over the texel's covered part (`texels.rs`), each seen as a white Lambertian surface:
//! cosine-weighted BSDF samples with MIS against the light system's samples, and every later bounce
//! as in `kelvin render` (`render::surface_paths`, the path tracer's own wavefront).
//!
//! **Leaks.** A sample whose first ray meets a back face nearer than the leak distance starts
//! inside geometry or behind a wall (a floor under a box, a wall's far side): it is dropped. The
//! back faces that count are those of one-sided materials and of closed meshes
//! ([`crate::geometry::ClosedSurfaces`]) whatever their material: Blender exports materials
//! double-sided by default, and a double-sided box still has an inside, while the back of an open
//! double-sided quad is a face (a two-sided lamp lights the ceiling with it). A sample inside
//! closed geometry meets a back face in every direction, so no sample under a box is kept,
//! whatever its ray. Texels left without a valid sample, and texels no triangle covers, are
//! filled from their valid neighbours, ring by ring, up to `margin` texels out (`lightmap.rs`):
//! bilinear filtering then reads no black fringe at a chart's edge.
//!
//! Output (`output.rs`): per lightmap an EXR (linear f32) and a zstd-supercompressed KTX2
//! (`B10G11R11_UFLOAT`, as Bevy's own lightmaps; [`ktx2`]), and `lightmaps.json`.
//!
//! [`bake_volume`] bakes an irradiance volume (ambient cubes for Bevy's `IrradianceVolume`) the
//! same way, from voxel centres instead of texels ([`volume`]).

pub mod ktx2;
mod lightmap;
mod output;
mod parts;
mod targets;
mod texels;
pub mod volume;

use std::ops::RangeInclusive;

use glam::Vec3;
use rayon::prelude::*;

pub use output::{LIGHTMAPS_JSON, write_lightmaps, write_volume};
pub use parts::{BakePart, Part, check_provenance};
pub use volume::{IrradianceVolume, VolumeOptions, bake_volume, bake_volume_part, merge_volume, node_bounds};

use crate::render::job::{self, LoadedJob};
use crate::render::path::PathDepth;
use crate::render::renderer::RenderStats;
use crate::render::surface_paths::{StartPoint, SurfaceTracer};
use crate::rng::SampleStream;
use crate::shading::{ColorMode, Settings};
use lightmap::Accumulator;

/// Accepted lightmap sides, texels.
pub const SIZE: RangeInclusive<u32> = 1..=4096;
/// Accepted dilation margins, texels.
pub const MARGIN: RangeInclusive<u32> = 0..=64;

/// Which light a lightmap holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum BakedLight {
    /// Direct and bounced light: a fully baked scene.
    #[default]
    All,
    /// Bounced light only, for scenes whose direct light stays real-time.
    Indirect,
}

/// How to bake.
#[derive(Clone, Debug, PartialEq)]
pub struct LightmapOptions {
    /// Side of every lightmap, texels ([`SIZE`]); with `texels_per_unit`, the largest side.
    /// Defaults to 256.
    pub size: u32,
    /// Texels per metre along the surface: each lightmap's side is chosen from its mesh's world
    /// area and the share of [0, 1]^2 its uv1 triangles cover (rounded up to a multiple of 4, at
    /// most `size`), so texels are about the same size in every mesh. None: every side is `size`.
    pub texels_per_unit: Option<f32>,
    /// Paths per texel ([`job::SPP`]). Defaults to 128.
    pub spp: u32,
    /// Surfaces after the texel's a path may reach, and where roulette may start ([`job::DEPTH`]).
    pub depth: PathDepth,
    /// All light or bounced light only. Defaults to all.
    pub light: BakedLight,
    /// How far (texels) dilation fills from valid texels ([`MARGIN`]). Defaults to 4.
    pub margin: u32,
    /// Passes of `spp` paths per texel until this many seconds have passed (at least one pass;
    /// [`job::SECONDS`]); None: one pass.
    pub time: Option<f64>,
    /// A sample whose first ray meets a back face nearer than this (m) is dropped as a leak;
    /// None: any back face in the scene (the diameter of its bounding sphere). A shorter
    /// distance keeps samples that see single-sided geometry from behind, farther away.
    pub leak_distance: Option<f32>,
}

impl Default for LightmapOptions {
    fn default() -> Self {
        Self {
            size: 256,
            texels_per_unit: None,
            spp: 128,
            depth: PathDepth::DEFAULT,
            light: BakedLight::All,
            margin: 4,
            time: None,
            leak_distance: None,
        }
    }
}

/// What a texel holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TexelState {
    /// Nothing: no triangle covers it (or none of its samples was valid) and dilation did not reach it. Zero.
    Empty,
    /// The mean of its valid samples.
    Baked,
    /// Filled by dilation from its neighbours.
    Filled,
}

/// One baked lightmap.
#[derive(Clone, Debug, PartialEq)]
pub struct Lightmap {
    /// A name unique in the bake: the glTF mesh's name (`mesh<index>` without one), followed by
    /// `.` and the node's name (or index) when the mesh is placed more than once. Files take it.
    pub name: String,
    /// The glTF mesh's name.
    pub mesh_name: Option<String>,
    /// The name of the node that places it.
    pub node_name: Option<String>,
    /// Side, texels.
    pub size: u32,
    /// Row-major, row 0 at v = 0 (the top, as glTF's uv has it): irradiance / pi, linear sRGB, nit.
    pub texels: Vec<Vec3>,
    /// Standard error of each baked texel's mean; zero elsewhere.
    pub std_error: Vec<Vec3>,
    /// What each texel holds.
    pub state: Vec<TexelState>,
    /// Samples dropped because their first ray met a back face nearby.
    pub leaked_samples: u64,
    /// World area (m^2) of the surfaces inside each texel; zero where none.
    pub area: Vec<f32>,
    /// Area-weighted diffuse albedo (linear sRGB) of the surfaces inside each texel: what an engine
    /// multiplies the texel by (Bevy's `diffuse_color`); zero where none.
    pub albedo: Vec<Vec3>,
}

impl Lightmap {
    /// Mean luminance (nit) of the baked texels, 0 without any.
    pub fn mean_luminance(&self) -> f32 {
        let baked = self.texels.iter().zip(&self.state).filter(|(_, s)| **s == TexelState::Baked);
        let (sum, n) = baked.fold((0.0f64, 0u32), |(sum, n), (t, _)| (sum + lightmap::luminance(*t) as f64, n + 1));
        if n == 0 { 0.0 } else { (sum / n as f64) as f32 }
    }
}

/// How far a bake is: `samples` of `of` paths traced (cells x spp; with a time budget, per pass),
/// and the finished fraction (of the time budget, with one).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Progress {
    /// Paths traced so far (in this pass, with a time budget).
    pub samples: u64,
    /// Paths of a pass: the bake's (or part's) cells times spp.
    pub of: u64,
    /// Finished share of the bake, 0 to 1.
    pub fraction: f32,
}

/// A finished bake.
#[derive(Clone, Debug, Default)]
pub struct BakeReport {
    /// One per placed mesh with TEXCOORD_1, in the file's order.
    pub lightmaps: Vec<Lightmap>,
    /// Meshes without TEXCOORD_1, one line each, skipped.
    pub skipped: Vec<String>,
    /// What else was dropped (uv1 outside [0, 1], degenerate triangles) and the light system's
    /// warnings.
    pub warnings: Vec<String>,
    /// Time, paths per texel (`spp`, more than asked under a time budget) and in all
    /// (`camera_samples`), shadow and BSDF rays, the light system's run report.
    pub stats: RenderStats,
}

/// Why a bake could not be done or written.
#[derive(Debug, thiserror::Error)]
pub enum BakeError {
    /// An option out of range or a world the bake cannot use; the message says which.
    #[error("{0}")]
    Invalid(String),
    /// No placed mesh has TEXCOORD_1.
    #[error("nothing to bake: {0}")]
    NothingToBake(String),
    /// An output file could not be encoded or written.
    #[error(transparent)]
    Write(#[from] crate::render::film_io::ImageIoError),
    /// A KTX2 file could not be encoded.
    #[error(transparent)]
    Ktx2(#[from] ktx2::Ktx2Error),
}

fn check_in<T: PartialOrd + std::fmt::Display>(name: &str, v: T, range: RangeInclusive<T>) -> Result<(), BakeError> {
    if range.contains(&v) {
        Ok(())
    } else {
        Err(BakeError::Invalid(format!("{name} = {v} is outside {}..={}", range.start(), range.end())))
    }
}

/// A time budget in [`job::SECONDS`], or none.
fn check_time(time: Option<f64>) -> Result<(), BakeError> {
    match time {
        Some(t) if !(t.is_finite() && job::SECONDS.contains(&t)) => {
            Err(BakeError::Invalid(format!("time = {t} is outside [0, {})", job::SECONDS.end)))
        }
        _ => Ok(()),
    }
}

impl LightmapOptions {
    /// Checks every option's range.
    pub fn check(&self) -> Result<(), BakeError> {
        check_in("size", self.size, SIZE)?;
        check_in("spp", self.spp, job::SPP)?;
        check_in("max_depth", self.depth.max_depth, job::DEPTH)?;
        check_in("roulette_depth", self.depth.roulette_depth, job::DEPTH)?;
        check_in("margin", self.margin, MARGIN)?;
        check_time(self.time)?;
        if let Some(d) = self.texels_per_unit
            && !(d > 0.0 && d.is_finite())
        {
            return Err(BakeError::Invalid(format!("texels_per_unit = {d} must be a positive finite density")));
        }
        match self.leak_distance {
            Some(d) if !(d > 0.0 && d.is_finite()) => {
                Err(BakeError::Invalid(format!("leak_distance = {d} must be a positive finite distance")))
            }
            _ => Ok(()),
        }
    }
}

impl LightmapOptions {
    /// The side of the lightmap of `surfaces`: `size`, or the one `texels_per_unit` asks for.
    fn side(&self, surfaces: &[texels::Surface]) -> u32 {
        let Some(density) = self.texels_per_unit else { return self.size };
        let (world, uv) = texels::areas(surfaces);
        if !(uv > 0.0 && world > 0.0) {
            return 4.min(self.size);
        }
        // A texel of 1/density m covers (1/density)^2 m^2, i.e. a 1/side^2 share of the atlas.
        let side = (density as f64 * (world / uv).sqrt()).ceil().min(*SIZE.end() as f64) as u32;
        side.next_multiple_of(4).clamp(1, self.size)
    }
}

/// Bakes a lightmap for every placed mesh of `loaded` that has TEXCOORD_1 (see the module's doc).
/// `progress` hears how far it is after each batch. The world must be in RGB colour mode.
pub fn bake_lightmaps(
    loaded: &mut LoadedJob,
    opts: &LightmapOptions,
    progress: impl FnMut(Progress) + Send,
) -> Result<BakeReport, BakeError> {
    let plan = LightmapPlan::new(loaded, opts)?;
    let (sums, stats) = plan.trace(loaded, opts, Part::WHOLE, progress);
    Ok(plan.finish(sums, stats, opts))
}

/// Part `part` of [`bake_lightmaps`]: the sums of its range of covered texels, every sample the
/// whole bake would take of them, for [`merge_lightmaps`]. A time budget cannot be split.
pub fn bake_lightmaps_part(
    loaded: &mut LoadedJob,
    opts: &LightmapOptions,
    part: Part,
    progress: impl FnMut(Progress) + Send,
) -> Result<BakePart, BakeError> {
    check_part(part, opts.time)?;
    let plan = LightmapPlan::new(loaded, opts)?;
    let (sums, stats) = plan.trace(loaded, opts, part, progress);
    Ok(BakePart::new("lightmaps", part, plan.cells(), sums, &stats))
}

/// The lightmaps of `parts` (every part of one bake of `loaded` with `opts`), bit for bit those of
/// [`bake_lightmaps`] with the same options. An error names a missing, overlapping or foreign part.
pub fn merge_lightmaps(
    loaded: &mut LoadedJob,
    opts: &LightmapOptions,
    parts: Vec<BakePart>,
) -> Result<BakeReport, BakeError> {
    let plan = LightmapPlan::new(loaded, opts)?;
    let (sums, stats) = parts::join("lightmaps", plan.cells(), parts)?;
    Ok(plan.finish(sums, stats, opts))
}

/// A split into parts needs a fixed number of samples per cell.
fn check_part(part: Part, time: Option<f64>) -> Result<(), BakeError> {
    part.check()?;
    if time.is_some() && part.count > 1 {
        return Err(BakeError::Invalid("a bake with a time budget cannot be split into parts; give spp".into()));
    }
    Ok(())
}

/// What a lightmap bake covers: the lightmaps, their sides and covered texels, and where each
/// lightmap's texels start among the bake's cells.
struct LightmapPlan {
    targets: Vec<targets::Target>,
    sides: Vec<u32>,
    coverages: Vec<texels::Coverage>,
    /// Texel ordinals over all lightmaps key the random streams: lightmap i's are first[i]..first[i + 1].
    first: Vec<u64>,
    /// Skipped meshes and coverage warnings.
    report: BakeReport,
}

impl LightmapPlan {
    fn new(loaded: &LoadedJob, opts: &LightmapOptions) -> Result<Self, BakeError> {
        opts.check()?;
        if loaded.world.resource::<Settings>().color_mode == ColorMode::Spectral {
            return Err(BakeError::Invalid("lightmaps are baked in RGB; the job's colour mode is spectral".into()));
        }
        let (targets, mut report) = targets::gather(&loaded.world, &loaded.primitives)?;
        let sides: Vec<u32> = targets.iter().map(|t| opts.side(&t.surfaces)).collect();
        let coverages: Vec<texels::Coverage> =
            targets.iter().zip(&sides).map(|(t, &side)| texels::Coverage::of(&t.surfaces, side)).collect();
        for (t, c) in targets.iter().zip(&coverages) {
            if c.outside > 0 {
                report.warnings.push(format!(
                    "{}: {} triangle(s) reach outside uv1 [0, 1]; that part is not baked",
                    t.name, c.outside
                ));
            }
            if c.texels.is_empty() {
                report
                    .warnings
                    .push(format!("{}: no texel covered (uv1 outside [0, 1] or of zero area); left empty", t.name));
            }
            if c.degenerate > 0 {
                report.warnings.push(format!(
                    "{}: {} triangle(s) of zero area in uv1 or in the world skipped",
                    t.name, c.degenerate
                ));
            }
        }
        let mut first = vec![0u64];
        first.extend(coverages.iter().scan(0u64, |n, c| {
            *n += c.texels.len() as u64;
            Some(*n)
        }));
        let cells = *first.last().unwrap_or(&0);
        if cells > u32::MAX as u64 {
            return Err(BakeError::Invalid(format!("{cells} covered texels: more than 2^32 - 1; use a smaller size")));
        }
        Ok(Self { targets, sides, coverages, first, report })
    }

    /// Covered texels over all lightmaps.
    fn cells(&self) -> u64 {
        *self.first.last().unwrap_or(&0)
    }

    /// The sums of `part`'s texels and the stats of tracing them.
    fn trace(
        &self,
        loaded: &mut LoadedJob,
        opts: &LightmapOptions,
        part: Part,
        progress: impl FnMut(Progress) + Send,
    ) -> (Vec<Accumulator>, RenderStats) {
        let LoadedJob { world, schedule, .. } = loaded;
        rayon::scope(|_| {
            let direct = opts.light == BakedLight::All;
            let mut tracer = SurfaceTracer::new(world, schedule, opts.depth, direct, opts.leak_distance);
            let (seed, pattern) = (tracer.seed(), tracer.pattern());
            let place = |t: u64, s: u32| {
                let map = self.first.partition_point(|&f| f <= t) - 1;
                let k = (t - self.first[map]) as usize;
                let mut rng = SampleStream::new(pattern, seed, t as u32, s).at_dimension(0);
                let u = [rng.next_f32(), rng.next_f32(), rng.next_f32()];
                self.coverages[map].point(&self.targets[map].surfaces, k, u, t as u32, s)
            };
            let passes = Passes { cells: part.range(self.cells()), spp: opts.spp, time: opts.time };
            let (sums, spp) = trace_all(world, schedule, &mut tracer, passes, place, progress);
            (sums, RenderStats { spp: spp.into(), ..tracer.stats })
        })
    }

    /// The finished lightmaps from every covered texel's sums.
    fn finish(self, sums: Vec<Accumulator>, stats: RenderStats, opts: &LightmapOptions) -> BakeReport {
        let mut report = self.report;
        report.stats = stats;
        report.warnings.extend(report.stats.report.warnings.iter().cloned());
        for (i, (target, coverage)) in self.targets.into_iter().zip(&self.coverages).enumerate() {
            let range = self.first[i] as usize..self.first[i + 1] as usize;
            report.lightmaps.push(lightmap::finish(target, coverage, &sums[range], self.sides[i], opts.margin));
        }
        report
    }
}

/// The sample counts of a bake: `spp` samples of each of the cells `cells` per pass, one pass,
/// or passes until `time` (seconds) has passed.
#[derive(Clone)]
struct Passes {
    cells: std::ops::Range<u64>,
    spp: u32,
    time: Option<f64>,
}

/// Traces the samples of `passes` in batches, sample `s` of cell `c` placed by `place(c, s)`, and
/// sums each cell's valid samples in sample order. Returns the sums (of cells `passes.cells`, in
/// order) and the samples per cell taken.
fn trace_all(
    world: &mut bevy_ecs::world::World,
    schedule: &mut bevy_ecs::schedule::Schedule,
    tracer: &mut SurfaceTracer,
    passes: Passes,
    place: impl Fn(u64, u32) -> StartPoint + Sync,
    mut progress: impl FnMut(Progress),
) -> (Vec<Accumulator>, u32) {
    let start = std::time::Instant::now();
    let Passes { cells, spp, time } = passes;
    let mut accumulators = vec![Accumulator::default(); (cells.end - cells.start) as usize];
    let mut points = Vec::with_capacity(SurfaceTracer::BATCH);
    // Samples are numbered from the range's first cell: sample g is of cell cells.start + g / spp.
    let total = (cells.end - cells.start) * spp as u64;
    for pass in 0u32.. {
        let mut first = 0u64;
        while first < total {
            let end = (first + SurfaceTracer::BATCH as u64).min(total);
            // Pass k takes samples k spp.. of each cell's streams.
            let sample = |g: u64| (cells.start + g / spp as u64, pass * spp + (g % spp as u64) as u32);
            let batch = (0..(end - first) as usize).into_par_iter().map(|i| sample(first + i as u64));
            batch.map(|(c, s)| place(c, s)).collect_into_vec(&mut points);
            let (rgb, leaked) = tracer.trace(world, schedule, &points);
            for (g, (rgb, leaked)) in (first..end).zip(rgb.iter().zip(leaked)) {
                accumulators[(g / spp as u64) as usize].add(rgb.as_dvec3(), *leaked);
            }
            first = end;
            let elapsed = start.elapsed().as_secs_f64();
            let fraction = time.map_or(first as f32 / total as f32, |t| (elapsed / t.max(1e-9)).min(1.0) as f32);
            progress(Progress { samples: first, of: total, fraction });
        }
        // Sample indices are u32: a pass that would run past them is not started.
        let room = pass.checked_add(2).and_then(|p| p.checked_mul(spp)).is_some();
        if time.is_none_or(|t| start.elapsed().as_secs_f64() >= t) || !room {
            tracer.stats.seconds = start.elapsed().as_secs_f64() + tracer.stats.update_seconds;
            return (accumulators, (pass + 1) * spp);
        }
    }
    unreachable!("the pass loop returns")
}

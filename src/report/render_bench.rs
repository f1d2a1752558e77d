//! The render suite: real glTF files rendered through the renderer's normal path, for speed.
//!
//! Each scene is a file of `tests/data` (origins in tests/data/SOURCES.md), loaded as
//! `kelvin render FILE [--env MAP]` loads it (`render::scene_file`) and rendered with
//! `render::renderer::render`: RGB, direct lighting with MIS, the light BVH, one light per sample,
//! the file's first camera or else one framing the scene. `kelvin bench render` prints the table,
//! `cargo bench --bench render` times the same scenes with criterion, and
//! bench/mitsuba/compare.py renders the same files with Mitsuba 3.
//!
//! **Timing**, as bench/mitsuba/mitsuba_gltf.py times Mitsuba: the file is loaded (timed on its
//! own), one 1-spp render brings the light system up to date (scene BVH, light table, light
//! sampler, environment tables: the cost of the first frame, reported as `seconds_setup`), then
//! `repeat` renders at the chosen spp are timed and the fastest counts. Each timed render is the
//! whole `render` call: camera pass, the light system's run per batch, shading and film.

use std::path::{Path, PathBuf};
use std::time::Instant;

use bevy_ecs::prelude::*;
use serde::Serialize;

use crate::render::job::{RenderJob, SamplerChoice};
use crate::render::renderer::{Integrator, PassSeconds, RenderOptions, RenderStats, Strategy, render};
use crate::render::scene_file::{spawn_env_map, spawn_gltf_file};
use crate::scene::spawn::SpawnReport;
use crate::shading::{ColorMode, Settings};
use crate::systems::LightingPlugin;

/// Errors of the suite: a message naming the scene or file.
pub type BenchError = Box<dyn std::error::Error + Send + Sync>;

/// One scene of the suite.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SuiteScene {
    /// Short name, as `--scenes` takes it.
    pub name: &'static str,
    /// The glTF file, relative to the data folder (tests/data).
    pub file: &'static str,
    /// Lat-long environment map relative to the data folder, lit at `env_intensity` (as
    /// `kelvin render --env MAP --env-intensity X`).
    pub env: Option<(&'static str, f32)>,
    /// Samples per pixel at 128x128 (other sizes keep the samples per image), chosen so that a
    /// render takes about a second or more on the 2-core development VM.
    pub spp_128: u32,
    /// What it exercises.
    pub about: &'static str,
}

/// The suite, in table order.
pub const SUITE: &[SuiteScene] = &[
    SuiteScene {
        name: "cornell_box",
        file: "gltf/bevy/CornellBox.glb",
        env: None,
        spp_128: 512,
        about: "one emissive quad (strength 100), glTF BRDF (roughness 0.5)",
    },
    SuiteScene {
        name: "points",
        file: "gltf/renderling/shadow_mapping_points.glb",
        env: None,
        spp_128: 512,
        about: "4 point lights over a floor with boxes",
    },
    SuiteScene {
        name: "spots",
        file: "gltf/renderling/spot_lights.glb",
        env: None,
        spp_128: 2048,
        about: "2 spot lights over a floor with boxes",
    },
    SuiteScene {
        name: "sphere_65k",
        file: "gltf/bench/sphere_65k.glb",
        env: None,
        spp_128: 1024,
        about: "65,536-triangle sphere over a floor, one point light, Lambertian",
    },
    SuiteScene {
        name: "emissive_strength",
        file: "gltf/renderling/EmissiveStrengthTest.glb",
        env: None,
        spp_128: 512,
        about: "60 emissive triangles (strengths 2-16)",
    },
    SuiteScene {
        name: "env_objects",
        file: "gltf/bench/env_objects.glb",
        env: Some(("env/spiaggia_di_mondello_1k.hdr", 1.0)),
        spp_128: 256,
        about: "boxes and spheres on a floor under a 1k HDR beach with a sun, Lambertian",
    },
    SuiteScene {
        name: "mixed_lighting",
        file: "gltf/bevy/MixedLightingExample/MixedLightingExample.gltf",
        env: None,
        spp_128: 2048,
        about: "textured PBR materials, one directional light",
    },
    SuiteScene {
        name: "scaling_10k",
        file: "gltf/bench/scaling_10k.glb",
        env: None,
        spp_128: 256,
        about: "the scaling scene at 10,000 point and spot lights, 1,250 spheres",
    },
];

/// The suite's scene called `name`.
pub fn suite_scene(name: &str) -> Option<&'static SuiteScene> {
    SUITE.iter().find(|s| s.name == name)
}

impl SuiteScene {
    /// Samples per pixel at `width` x `height`: as many camera samples as `spp_128` at 128x128,
    /// at least one per pixel.
    pub fn default_spp(&self, width: u32, height: u32) -> u32 {
        let samples = self.spp_128 as u64 * 128 * 128;
        (samples / (width as u64 * height as u64).max(1)).max(1) as u32
    }

    /// The world and schedule the renderer takes: the suite's settings (RGB, light BVH, one light
    /// per sample), `LightingPlugin`, the file's entities and the environment map if any.
    pub fn world(&self, data_dir: &Path) -> Result<(World, Schedule, SpawnReport), BenchError> {
        self.world_with(data_dir, SamplerChoice::Bvh)
    }

    /// [`Self::world`] with lights chosen by `sampler` (RIS and ReSTIR with `kelvin render`'s
    /// default candidates and neighbours).
    pub fn world_with(
        &self,
        data_dir: &Path,
        sampler: SamplerChoice,
    ) -> Result<(World, Schedule, SpawnReport), BenchError> {
        let mut world = World::new();
        let mut schedule = Schedule::default();
        let job = RenderJob { light_sampler: sampler, ..RenderJob::default() };
        world.insert_resource(Settings {
            color_mode: ColorMode::Rgb,
            light_sampler: job.settings().light_sampler,
            selection: job.selection(),
            ..Default::default()
        });
        LightingPlugin::build(&mut world, &mut schedule);
        let mut report = spawn_gltf_file(&mut world, &data_dir.join(self.file))?;
        if let Some((map, intensity)) = self.env {
            report.warnings.extend(spawn_env_map(&mut world, &data_dir.join(map), intensity)?);
        }
        Ok((world, schedule, report))
    }
}

/// The render options of the suite: MIS, `width` x `height`, `spp`, `integrator`.
pub fn suite_options(width: u32, height: u32, spp: u32, integrator: Integrator) -> RenderOptions {
    RenderOptions { width, height, spp: spp.max(1), strategy: Strategy::Mis, integrator, ..Default::default() }
}

/// How a row names its integrator: "direct", or "path, depth N".
pub fn integrator_name(integrator: Integrator) -> String {
    match integrator {
        Integrator::Direct => "direct".into(),
        Integrator::Path(depth) => format!("path, depth {}", depth.max_depth),
    }
}

/// What to run.
#[derive(Clone, Debug)]
pub struct RenderBenchConfig {
    /// Folder of the real test data (tests/data).
    pub data_dir: PathBuf,
    /// Image width, pixels (at least 1 is used).
    pub width: u32,
    /// Image height, pixels (at least 1 is used).
    pub height: u32,
    /// Samples per pixel for every scene; each scene's `default_spp` when None.
    pub spp: Option<u32>,
    /// Timed renders per scene; the fastest counts.
    pub repeat: usize,
    /// Scene names; the whole suite when empty.
    pub scenes: Vec<String>,
    /// Direct lighting (the default, as Mitsuba's `direct`) or the path tracer (Mitsuba's `path`).
    pub integrator: Integrator,
    /// How lights are chosen (the light BVH by default).
    pub light_sampler: SamplerChoice,
}

impl Default for RenderBenchConfig {
    fn default() -> Self {
        Self {
            data_dir: PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data")),
            width: 128,
            height: 128,
            spp: None,
            repeat: 3,
            scenes: Vec::new(),
            integrator: Integrator::Direct,
            light_sampler: SamplerChoice::Bvh,
        }
    }
}

/// Seconds of each pass of the fastest render (see `PassSeconds`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct PassRow {
    /// Camera rays and their closest hits.
    pub camera: f64,
    /// The light system: light choice, Sample_Li and shadow rays.
    pub light_system: f64,
    /// MIS with BSDF samples and adding the samples to the film.
    pub shading: f64,
}

impl From<PassSeconds> for PassRow {
    fn from(p: PassSeconds) -> Self {
        Self { camera: p.camera, light_system: p.light_system, shading: p.shading }
    }
}

/// One scene's measurement. Rates are per second of the fastest timed render.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RenderBenchRow {
    /// The suite scene's name.
    pub scene: String,
    /// The glTF file and the environment map, as paths (absolute when `data_dir` is).
    pub file: String,
    /// The environment map, if the scene has one (see `file`).
    pub env: Option<String>,
    /// Luminance of an environment texel of value 1, nit.
    pub env_intensity: Option<f32>,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Samples per pixel of the timed renders.
    pub spp: u32,
    /// The integrator ([`integrator_name`]).
    pub integrator: String,
    /// How lights were chosen: bvh, uniform, power, ris or restir.
    pub light_sampler: String,
    /// Rayon worker threads.
    pub threads: usize,
    /// Meshes spawned from the file.
    pub meshes: usize,
    /// Triangles spawned from the file.
    pub triangles: usize,
    /// Punctual and IES lights spawned from the file (emissive meshes not counted).
    pub lights: usize,
    /// Cameras in the file.
    pub cameras: usize,
    /// Loading the file and the map and spawning them.
    pub seconds_load: f64,
    /// The 1-spp render that builds the scene BVH, light table, sampler and env tables.
    pub seconds_setup: f64,
    /// The fastest timed render, s.
    pub seconds_best: f64,
    /// Every timed render, s, in order.
    pub seconds_all: Vec<f64>,
    /// Counts of one render.
    pub camera_samples: u64,
    /// Shadow rays traced by the light system.
    pub shadow_rays: u64,
    /// BSDF-sampled rays traced for MIS.
    pub bsdf_rays: u64,
    /// Camera samples per second.
    pub samples_per_s: f64,
    /// Shadow rays per second.
    pub shadow_rays_per_s: f64,
    /// BSDF rays per second.
    pub bsdf_rays_per_s: f64,
    /// Time of each pass of the fastest render.
    pub passes: PassRow,
    /// Loader and light-system warnings.
    pub warnings: Vec<String>,
}

/// The scenes `cfg` names, in suite order; an error names an unknown one.
pub fn selected_scenes(cfg: &RenderBenchConfig) -> Result<Vec<&'static SuiteScene>, BenchError> {
    for name in &cfg.scenes {
        if suite_scene(name).is_none() {
            let names: Vec<&str> = SUITE.iter().map(|s| s.name).collect();
            return Err(format!("--scenes: unknown scene '{name}'; the suite has: {}", names.join(", ")).into());
        }
    }
    Ok(SUITE.iter().filter(|s| cfg.scenes.is_empty() || cfg.scenes.iter().any(|n| n == s.name)).collect())
}

/// Loads, sets up and times one scene.
pub fn run_scene(scene: &SuiteScene, cfg: &RenderBenchConfig) -> Result<RenderBenchRow, BenchError> {
    let (width, height) = (cfg.width.max(1), cfg.height.max(1));
    let spp = cfg.spp.unwrap_or_else(|| scene.default_spp(width, height)).max(1);
    let load_start = Instant::now();
    let (mut world, mut schedule, spawned) =
        scene.world_with(&cfg.data_dir, cfg.light_sampler).map_err(|e| format!("scene {}: {e}", scene.name))?;
    let seconds_load = load_start.elapsed().as_secs_f64();
    let (_, setup) = render(&mut world, &mut schedule, &suite_options(width, height, 1, cfg.integrator), |_| {});
    let mut warnings = spawned.warnings.clone();
    warnings.extend(setup.report.warnings.iter().cloned());
    let opts = suite_options(width, height, spp, cfg.integrator);
    let mut best: Option<RenderStats> = None;
    let mut seconds_all = Vec::new();
    for _ in 0..cfg.repeat.max(1) {
        let (_, stats) = render(&mut world, &mut schedule, &opts, |_| {});
        seconds_all.push(stats.seconds);
        if best.as_ref().is_none_or(|b| stats.seconds < b.seconds) {
            best = Some(stats);
        }
    }
    let best = best.expect("at least one timed render");
    let secs = best.seconds.max(1e-12);
    let path = |rel: &str| cfg.data_dir.join(rel).display().to_string();
    Ok(RenderBenchRow {
        scene: scene.name.to_string(),
        file: path(scene.file),
        env: scene.env.map(|(map, _)| path(map)),
        env_intensity: scene.env.map(|(_, x)| x),
        width,
        height,
        spp,
        integrator: integrator_name(cfg.integrator),
        light_sampler: format!("{:?}", cfg.light_sampler).to_lowercase(),
        threads: rayon::current_num_threads(),
        meshes: spawned.meshes,
        triangles: spawned.triangles,
        lights: spawned.lights,
        cameras: spawned.cameras,
        seconds_load,
        seconds_setup: setup.seconds,
        seconds_best: best.seconds,
        seconds_all,
        camera_samples: best.camera_samples,
        shadow_rays: best.shadow_rays,
        bsdf_rays: best.bsdf_rays,
        samples_per_s: best.camera_samples as f64 / secs,
        shadow_rays_per_s: best.shadow_rays as f64 / secs,
        bsdf_rays_per_s: best.bsdf_rays as f64 / secs,
        passes: best.passes.into(),
        warnings,
    })
}

/// Runs the scenes `cfg` selects, one after another; `progress` hears each scene's name and row.
pub fn run_render_bench(
    cfg: &RenderBenchConfig,
    mut progress: impl FnMut(&str),
) -> Result<Vec<RenderBenchRow>, BenchError> {
    let mut rows = Vec::new();
    for scene in selected_scenes(cfg)? {
        progress(&format!("{}: {} ({})", scene.name, scene.file, scene.about));
        let row = run_scene(scene, cfg)?;
        progress(&format!(
            "{}: load {:.3} s, setup {:.3} s, renders {:?} s",
            row.scene,
            row.seconds_load,
            row.seconds_setup,
            row.seconds_all.iter().map(|s| (s * 1000.0).round() / 1000.0).collect::<Vec<_>>()
        ));
        rows.push(row);
    }
    Ok(rows)
}

/// The table: scene, size, spp, seconds, and millions of camera samples, shadow rays and BSDF
/// rays per second (of the fastest render), as Markdown.
pub fn format_table(rows: &[RenderBenchRow]) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "| scene | integrator | lights | size | spp | seconds | M samples/s | M shadow rays/s | M BSDF rays/s |"
    );
    let _ = writeln!(s, "|---|---|---|---|---:|---:|---:|---:|---:|");
    for r in rows {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {}x{} | {} | {:.3} | {:.2} | {:.2} | {:.2} |",
            r.scene,
            r.integrator,
            r.light_sampler,
            r.width,
            r.height,
            r.spp,
            r.seconds_best,
            r.samples_per_s / 1e6,
            r.shadow_rays_per_s / 1e6,
            r.bsdf_rays_per_s / 1e6
        );
    }
    s
}

/// The rows as one line of JSON: `{"suite": "kelvin render", "rows": [...]}`.
pub fn to_json(rows: &[RenderBenchRow]) -> String {
    serde_json::json!({ "suite": "kelvin bench render", "rows": rows }).to_string()
}

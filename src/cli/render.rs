//! `kelvin render [SCENE] [-o out.exr] [--spp N] [--time SECONDS] [--size WxH] [--env map [--env-intensity X]]
//! [--sky LAT,LON,YYYY-MM-DDTHH:MM[,TURBIDITY] [--sky-intensity X]] [--integrator path|direct] [--max-depth N]
//! [--roulette-depth N] [--light-sampler uniform|power|bvh|ris|restir [--candidates M]
//! [--neighbours K] [--radius PX] [--biased-reuse]] [--color rgb|spectral] [--seed S] [--pattern sobol|independent]
//! [--threads T] [--report] [--crop X0,Y0,X1,Y1] [--frames 0..47|1-100x2|1,5,10-20|-5--1 [--fps F]
//! [--animation NAME|INDEX]]`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use bevy_ecs::prelude::*;
use indicatif::{ProgressBar, ProgressStyle};
use kelvin::provenance::{INPUT_PREFIX, Provenance, file_sha256};
use kelvin::render::film_io::{auto_exposure, write_exr_tile, write_exr_with, write_png_with};
use kelvin::render::job::{self, IntegratorChoice, LoadedJob, RenderJob, SamplerChoice};
use kelvin::render::path::PathDepth;
use kelvin::render::renderer::{RenderOptions, RenderStats, render_with};
use kelvin::render::tiles::Crop;
use kelvin::rng::Pattern;
use kelvin::scene::animate::{GltfAnimations, pose_gltf};
use kelvin::shading::ColorMode;

use super::frames::{FrameRange, frame_output};
use super::{CliError, values};

#[derive(clap::Args)]
pub struct RenderArgs {
    /// glTF scene (.gltf or .glb); the embedded default scene when absent.
    scene: Option<PathBuf>,
    /// Output image: .exr (linear, photometric) or .png (tone-mapped). An .exr also gets a .png preview.
    #[arg(short, long, default_value = "render.exr")]
    output: PathBuf,
    /// Camera samples per pixel (per pass, with --time).
    #[arg(long, default_value_t = 32, value_parser = values::whole(job::SPP))]
    spp: u32,
    /// Render passes of --spp samples per pixel until this many seconds have passed (at least one).
    #[arg(long, value_name = "SECONDS", value_parser = values::seconds)]
    time: Option<f64>,
    /// Image size as WIDTHxHEIGHT.
    #[arg(long, default_value = "512x512", value_parser = values::size)]
    size: (u32, u32),
    #[command(flatten)]
    lighting: LightingArgs,
    /// How light reaches the camera: paths of up to --max-depth bounces, every bounce through the
    /// light system, or direct lighting (light and BSDF samples at the surface the camera sees).
    #[arg(long, value_enum, default_value = "path")]
    integrator: IntegratorChoice,
    /// Path tracer: surfaces after the camera's at most (1 = direct lighting, 0 = emission only).
    #[arg(long, default_value_t = PathDepth::DEFAULT.max_depth, value_parser = values::whole(job::DEPTH))]
    max_depth: u32,
    /// Path tracer: Russian roulette may end a path from this many surfaces on.
    #[arg(long, default_value_t = PathDepth::DEFAULT.roulette_depth, value_parser = values::whole(job::DEPTH))]
    roulette_depth: u32,
    /// How a light is chosen per sample (ris: resampled importance sampling over --candidates
    /// light-BVH samples, one shadow ray for the one it keeps; restir: ris, then each pixel's
    /// reservoir combined with --neighbours others' within --radius pixels).
    #[arg(long, value_enum, default_value = "bvh")]
    light_sampler: SamplerChoice,
    /// Colour mode.
    #[arg(long, value_enum, default_value = "rgb")]
    color: ColorMode,
    /// Light samples drawn per resampled one (--light-sampler ris or restir; default 8).
    #[arg(long, value_parser = values::whole(job::CANDIDATES))]
    candidates: Option<u32>,
    /// Neighbour reservoirs combined per pixel (--light-sampler restir; default 4).
    #[arg(long, value_parser = values::whole(job::NEIGHBOURS))]
    neighbours: Option<u32>,
    /// Radius of the neighbourhood, pixels (--light-sampler restir; default 16).
    #[arg(long, value_parser = values::whole(job::RADIUS))]
    radius: Option<u32>,
    /// Weigh combined reservoirs 1/sum M: fewer target evaluations, biased (--light-sampler restir).
    #[arg(long)]
    biased_reuse: bool,
    /// Sample every light at every point instead of one chosen light.
    #[arg(long)]
    all_lights: bool,
    /// Light sampling only (no MIS with BSDF sampling).
    #[arg(long)]
    no_mis: bool,
    /// Seed of the random numbers.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Random numbers of the samples: Owen-scrambled Sobol (stratified: smooth light converges
    /// faster than 1/spp) or independent.
    #[arg(long, value_enum, default_value = "sobol")]
    pattern: Pattern,
    /// Worker threads (default: all cores). Output is bit-identical for any count.
    #[arg(long, value_parser = values::threads())]
    threads: Option<usize>,
    /// PNG exposure in stops; automatic (mean log luminance to 18% grey) when absent.
    #[arg(long, value_parser = values::exposure())]
    exposure: Option<f32>,
    /// Render a lat-long radiance map seen from this point (an environment camera), e.g. 0,1,0,
    /// instead of the scene's camera; the EXR can light another scene with --env.
    #[arg(long, value_name = "X,Y,Z", value_parser = values::point)]
    environment_at: Option<glam::Vec3>,
    /// Render only this tile of the image (pixels X0..X1 by Y0..Y1, ends exclusive), bit for bit as
    /// in the full render, into an EXR that records its place (`kelvin merge` joins tiles).
    #[arg(long, value_name = "X0,Y0,X1,Y1", value_parser = values::crop)]
    crop: Option<Crop>,
    /// Render these frames of the scene's animation in one process, in ascending order, each
    /// moving only what the animation moves; the output's run of '#' takes the frame number
    /// (-o out_####.exr; its folders are created). A frame list as OpenCue and Deadline write it:
    /// 7; 0..47 or 1-100, both ends included; -5--1, negative frames (before the clip: its first
    /// pose); 1-100x2 every other frame; 1-10y3 the frames 1-10x3 leaves out; 1-10:3 all of 1-10
    /// (an interleave's frames); 100-1x5 and 1:100:5 as Deadline writes them; 1,5,10-20 or 1 5 10-20.
    #[arg(long, value_name = "FRAMES", allow_hyphen_values = true)]
    frames: Option<FrameRange>,
    /// Frames per second: frame k shows the animation at k / fps seconds.
    #[arg(long, default_value_t = 24.0, value_parser = values::fps)]
    fps: f64,
    /// The animation --frames plays, by name or index.
    #[arg(long, default_value = "0")]
    animation: String,
    /// Print the light system's run report over the whole render (which systems ran in how many
    /// of its updates, with counts summed over the batches, why others were skipped, and every
    /// warning), and the time of each pass.
    #[arg(long)]
    report: bool,
    /// Append the start (output, host, pid), progress (`progress N%` lines, every 5% and at least
    /// every 30 s) and the outcome with its exit code to this file (its folder created), a line at a
    /// time with the UTC time, as `kelvin batch --log` does, for a farm's monitor to tail. The same
    /// lines but the outcome go to stderr when it is not a terminal (the error is printed there anyway).
    #[arg(long, value_name = "FILE")]
    log: Option<PathBuf>,
}

/// The lights a job adds to its scene: an environment map or a sun and sky (`render`, `bake`).
#[derive(clap::Args)]
pub(super) struct LightingArgs {
    /// Lat-long environment map (.exr or .hdr) lighting the scene as an infinite light.
    #[arg(long, value_parser = values::existing_file)]
    pub(super) env: Option<PathBuf>,
    /// Luminance (nit) of an environment texel of value 1.
    #[arg(long, default_value_t = 1.0, value_parser = values::intensity())]
    pub(super) env_intensity: f32,
    /// A physical sun and sky (Hosek-Wilkie) for a place and a UTC time: latitude (degrees north),
    /// longitude (degrees east), UTC date-time, optional turbidity 1-10 (default 3), e.g.
    /// 48.86,2.35,2024-06-21T10:00 or 48.86,2.35,2024-06-21T10:00,5. +Y is up, -Z north. Replaces
    /// the sky a scene file carries (its KELVIN_sun_sky extension).
    #[arg(long, value_name = "LAT,LON,YYYY-MM-DDTHH:MM[,TURBIDITY]")]
    pub(super) sky: Option<String>,
    /// Multiplies the sky's physical radiance (1 = real daylight, ~100 klx in full sun); also a
    /// scene file's own sky.
    #[arg(long, default_value_t = 1.0, value_parser = values::intensity())]
    pub(super) sky_intensity: f32,
}

impl LightingArgs {
    /// `job` with these lights.
    pub(super) fn apply(&self, job: RenderJob) -> RenderJob {
        RenderJob {
            env: self.env.clone(),
            env_intensity: self.env_intensity,
            sky: self.sky.clone(),
            sky_intensity: self.sky_intensity,
            ..job
        }
    }
}

impl RenderArgs {
    /// The full image's size.
    pub(super) fn size(&self) -> (u32, u32) {
        self.size
    }

    /// The PNG exposure, stops (None: automatic).
    pub(super) fn exposure(&self) -> Option<f32> {
        self.exposure
    }

    /// The animation --frames plays, as given (a name or an index).
    pub(super) fn animation(&self) -> &str {
        &self.animation
    }

    /// The render these arguments describe (all but outputs and frames).
    pub(super) fn job(&self) -> RenderJob {
        self.lighting.apply(RenderJob {
            scene: self.scene.clone(),
            width: self.size.0,
            height: self.size.1,
            spp: self.spp,
            time: self.time,
            integrator: self.integrator,
            depth: PathDepth { max_depth: self.max_depth, roulette_depth: self.roulette_depth },
            light_sampler: self.light_sampler,
            candidates: self.candidates,
            neighbours: self.neighbours,
            radius: self.radius,
            biased_reuse: self.biased_reuse,
            color: self.color,
            all_lights: self.all_lights,
            mis: !self.no_mis,
            seed: self.seed,
            pattern: self.pattern,
            environment_at: self.environment_at,
            crop: self.crop,
            ..RenderJob::default()
        })
    }

    /// What an output of frame `frame` (None without --frames) of the animation `clip` (its index
    /// and name, once resolved) records: the program, `inputs` (the SHA-256 of each file the render
    /// read, as read: [`kelvin::provenance::Inputs::entries`]), every setting that shapes the pixels
    /// (a PNG's exposure too), the frame, the clip and the tile. Tiles of one image differ in `tile` only.
    pub(super) fn provenance(
        &self,
        frame: Option<i32>,
        clip: Option<(usize, Option<&str>)>,
        inputs: BTreeMap<String, String>,
    ) -> Provenance {
        // Paths differ between machines; the files' contents are what matter.
        let job = RenderJob { scene: None, env: None, crop: None, ..self.job() };
        let mut p = Provenance::of_program().with("settings", format!("{job:?}")).with_all(inputs);
        if self.scene.is_none() {
            p = p.with("scene", "the embedded default scene");
        }
        if self.output.extension().is_some_and(|e| e.eq_ignore_ascii_case("png")) {
            p = p.with("exposure", self.exposure.map_or("auto".to_owned(), |e| e.to_string()));
        }
        if let Some(f) = frame {
            p = p.with("frame", f.to_string()).with("fps", self.fps.to_string());
        }
        if let Some((index, name)) = clip {
            p = p.with("animation", index.to_string()).with("animation_name", name.unwrap_or_default());
        }
        if let Some(crop) = self.crop {
            p = p.with("tile", crop.to_string());
        }
        p
    }

    /// The input entries an output recording `recorded` would have if made now: the scene and
    /// environment map this job names, and each file `recorded` lists (`input <path>`, beside the
    /// scene), hashed now. A done-check compares them with what was recorded when read.
    pub(super) fn inputs_now(&self, recorded: &Provenance) -> Result<BTreeMap<String, String>, String> {
        inputs_now(self.scene.as_deref(), self.lighting.env.as_deref(), recorded.0.keys())
    }

    /// The files the render reads by name (scene, environment map) and those the scene references
    /// (buffers, images, IES profiles, from its JSON): what each machine of a farm must hold with
    /// the same contents.
    pub(super) fn input_files(&self) -> Vec<PathBuf> {
        let referenced = self.scene.iter().flat_map(|s| kelvin::scene::gltf::referenced_files(s));
        self.scene.iter().chain(&self.lighting.env).cloned().chain(referenced).collect()
    }

    /// Why this render cannot be split into tiles that merge into it (None: it can).
    pub(super) fn tiling_refusal(&self) -> Option<String> {
        let job = self.job();
        let whole = RenderOptions { crop: Some(Crop { x0: 0, y0: 0, x1: 1, y1: 1 }), ..job.options() };
        whole.check_tiling(&job.selection()).err().map(|e| e.to_string())
    }
}

/// The input entries ([`kelvin::provenance::Inputs::entries`]) of `scene`, `env` and each
/// `input <path>` among `recorded` keys (beside the scene), hashed now: what a done-check
/// compares with the digests an output recorded when its inputs were read.
pub(super) fn inputs_now<'a>(
    scene: Option<&Path>,
    env: Option<&Path>,
    recorded: impl Iterator<Item = &'a String>,
) -> Result<BTreeMap<String, String>, String> {
    let hash = |p: &Path| file_sha256(p).map_err(|e| format!("{}: {e}", p.display()));
    let mut now = BTreeMap::new();
    if let Some(scene) = scene {
        now.insert("scene".to_owned(), hash(scene)?);
    }
    if let Some(env) = env {
        now.insert("env".to_owned(), hash(env)?);
    }
    let base = scene.and_then(Path::parent).unwrap_or(Path::new(""));
    for key in recorded {
        if let Some(rel) = key.strip_prefix(INPUT_PREFIX) {
            now.insert(key.clone(), hash(&base.join(rel))?);
        }
    }
    Ok(now)
}

/// Loads the job's world, printing the loader's warnings and the scene's summary.
fn build_world(job: &RenderJob) -> Result<LoadedJob, CliError> {
    let loaded = job.load()?;
    for w in &loaded.warnings {
        eprintln!("warning: {w}");
    }
    if let Some(summary) = &loaded.summary {
        eprintln!("{summary}");
    }
    Ok(loaded)
}

/// The index of the animation `--animation` names in the spawned file, or why there is none.
fn chosen_clip(world: &World, file: Option<usize>, args: &RenderArgs) -> Result<usize, CliError> {
    let scene = args.scene.as_ref().map_or("the default scene".to_string(), |p| p.display().to_string());
    let files = world.get_resource::<GltfAnimations>().map_or(&[][..], |a| &a.files);
    let Some(animations) = file.and_then(|f| files.get(f)).filter(|a| !a.clips.is_empty()) else {
        return Err(format!("--frames: {scene} has no animation").into());
    };
    animations.find(&args.animation).ok_or_else(|| {
        let clips = animations.clips.iter().enumerate();
        let names: Vec<String> = clips.map(|(i, c)| format!("{i}: {}", c.name.as_deref().unwrap_or("-"))).collect();
        format!("--animation {}: not in {scene} (it has {})", args.animation, names.join(", ")).into()
    })
}

/// Writes the image, and beside an .exr a .png preview first (so that an .exr that exists is a
/// finished render's, preview included: `kelvin batch` skips it).
pub(super) fn write_outputs(
    path: &Path,
    w: u32,
    h: u32,
    rgb: &[glam::Vec3],
    exposure: f32,
    provenance: &Provenance,
) -> Result<(), CliError> {
    let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
    match ext.as_str() {
        "exr" => {
            let preview = path.with_extension("png");
            write_png_with(&preview, w as usize, h as usize, rgb, exposure, Some(provenance))?;
            write_exr_with(path, w as usize, h as usize, rgb, provenance)?;
            eprintln!("wrote {} and {}", path.display(), preview.display());
        }
        "png" => {
            write_png_with(path, w as usize, h as usize, rgb, exposure, Some(provenance))?;
            eprintln!("wrote {}", path.display());
        }
        _ => return Err(format!("{}: unsupported output extension; use .exr or .png", path.display()).into()),
    }
    Ok(())
}

/// One rendered image: its frame (with --frames), the time posing the frame took, and the
/// render's statistics.
pub(super) struct Rendered {
    pub frame: Option<i32>,
    pub pose_seconds: f64,
    pub stats: RenderStats,
}

/// Renders as `args` say and writes the outputs, one per frame with --frames; `progress` gets
/// the finished fraction.
pub(super) fn render_to_files(
    args: &RenderArgs,
    mut progress: impl FnMut(f32) + Send,
) -> Result<Vec<Rendered>, CliError> {
    let (width, height) = args.size;
    let job = args.job();
    let opts = job.options();
    let ext = args.output.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
    let out = args.output.display();
    if let Some(crop) = args.crop {
        crop.check(width, height)?;
        if ext.as_deref() != Some("exr") {
            return Err(format!(
                "--output {out}: a --crop tile is written as .exr, which records its place in the image"
            )
            .into());
        }
        opts.check_tiling(&job.selection()).map_err(|e| format!("--crop {crop}: {e}"))?;
    } else if !matches!(ext.as_deref(), Some("exr" | "png")) {
        return Err(format!("--output {out}: unsupported output extension; use .exr or .png").into());
    }
    // Checked before the scene loads, so a bad name fails at once, and the folders made then, so a
    // folder that cannot be made fails before the render rather than after its first frame.
    let (frames, outputs): (Vec<Option<i32>>, Vec<PathBuf>) = match &args.frames {
        Some(range) => {
            let outputs = range.iter().map(|f| frame_output(&args.output, range, f)).collect::<Result<_, _>>()?;
            (range.iter().map(Some).collect(), outputs)
        }
        None => (vec![None], vec![args.output.clone()]),
    };
    create_folders(&outputs)?;
    let LoadedJob { mut world, mut schedule, file, inputs, .. } = build_world(&job)?;
    // Hashed when read: a file replaced during the render does not speak for this image.
    let inputs = inputs.entries();
    let clip = if args.frames.is_some() { Some(chosen_clip(&world, file, args)?) } else { None };
    let camera = job.camera();
    let mut rendered = Vec::with_capacity(frames.len());
    let n = frames.len() as f32;
    for (k, frame) in frames.into_iter().enumerate() {
        let (output, pose_seconds) = match (frame, &args.frames, clip, file) {
            (Some(f), Some(_), Some(clip), Some(file)) => {
                let start = std::time::Instant::now();
                let posed = pose_gltf(&mut world, file, clip, (f64::from(f) / args.fps) as f32)?;
                if k == 0 && posed.frozen > 0 {
                    eprintln!(
                        "warning: {} animated meshes have a singular rest transform and stay at rest",
                        posed.frozen
                    );
                }
                (outputs[k].clone(), start.elapsed().as_secs_f64())
            }
            _ => (args.output.clone(), 0.0),
        };
        let (film, stats) = render_with(&mut world, &mut schedule, &opts, camera, |f| progress((k as f32 + f) / n));
        let clip_name = |c: usize| {
            let files = world.get_resource::<GltfAnimations>().map(|a| &a.files);
            let clip = files.and_then(|f| f.get(file?)).and_then(|a| a.clips.get(c));
            clip.and_then(|c| c.name.clone())
        };
        let clip = clip.map(|c| (c, clip_name(c)));
        let clip = clip.as_ref().map(|(c, n)| (*c, n.as_deref()));
        write_image(args, &output, &film.pixels(), &args.provenance(frame, clip, inputs.clone()))?;
        rendered.push(Rendered { frame, pose_seconds, stats });
    }
    Ok(rendered)
}

/// Creates the folders of `outputs` (once each: a sequence's frames share theirs).
fn create_folders(outputs: &[PathBuf]) -> Result<(), CliError> {
    let mut made: Vec<&Path> = Vec::new();
    for output in outputs {
        let Some(dir) = output.parent().filter(|d| !d.as_os_str().is_empty() && !made.contains(d)) else { continue };
        let what = format!("{}: cannot write: cannot create its folder {}", output.display(), dir.display());
        std::fs::create_dir_all(dir).map_err(super::exit::io(what))?;
        made.push(dir);
    }
    Ok(())
}

/// Writes one render: a tile's EXR, or the image and its preview.
fn write_image(args: &RenderArgs, output: &Path, rgb: &[glam::Vec3], provenance: &Provenance) -> Result<(), CliError> {
    let (width, height) = args.size;
    match args.crop {
        // No preview: a tile's automatic exposure is not the image's (`kelvin merge` writes that).
        Some(crop) => {
            write_exr_tile(output, crop, width, height, rgb, provenance)?;
            eprintln!("wrote {} (tile {crop} of {width}x{height})", output.display());
        }
        None => {
            let exposure = args.exposure.unwrap_or_else(|| auto_exposure(rgb));
            write_outputs(output, width, height, rgb, exposure, provenance)?;
        }
    }
    Ok(())
}

/// A progress bar of 1000 steps.
pub(super) fn progress_bar() -> ProgressBar {
    let bar = ProgressBar::new(1000);
    bar.set_style(
        ProgressStyle::with_template("{msg}{bar:40} {percent:>3}% {elapsed_precise} eta {eta}")
            .expect("valid template"),
    );
    bar
}

pub fn run(args: RenderArgs) -> Result<(), CliError> {
    if let Some(t) = args.threads {
        rayon::ThreadPoolBuilder::new().num_threads(t).build_global()?;
    }
    // A bar on a terminal; progress lines when a farm's task runner reads stderr (and in --log).
    let log = super::task_log::TaskLog::open(args.log.as_deref())?;
    log.line(&format!(
        "kelvin render {}: host {}, pid {}",
        args.output.display(),
        kelvin::render::partial::this_host(),
        std::process::id()
    ));
    let mut progress = log.job(0, 1, &args.output.display().to_string());
    let started = std::time::Instant::now();
    let rendered = render_to_files(&args, |f| progress.set(f));
    progress.finish();
    let rendered = match rendered {
        Ok(r) => {
            log.to_file_only(&format!(
                "rendered {} in {:.1} s",
                args.output.display(),
                started.elapsed().as_secs_f64()
            ));
            r
        }
        Err(e) => {
            log.to_file_only(&format!("failed (exit code {}): {e}", super::exit_code(&*e)));
            return Err(e);
        }
    };
    let (width, height) = args.crop.map_or(args.size, |c| (c.width(), c.height()));
    for Rendered { frame, pose_seconds, stats, .. } in rendered {
        if let Some(f) = frame {
            println!(
                "frame {f} (t = {:.4} s): pose {:.3} ms, light system update {:.3} ms",
                f64::from(f) / args.fps,
                pose_seconds * 1e3,
                stats.update_seconds * 1e3
            );
        }
        let secs = stats.seconds.max(1e-9);
        println!(
            "rendered {width}x{height} at {} spp in {:.3} s: {:.2} M samples/s, {:.2} M shadow rays/s, {:.2} M BSDF rays/s",
            stats.spp,
            stats.seconds,
            stats.camera_samples as f64 / secs / 1e6,
            stats.shadow_rays as f64 / secs / 1e6,
            stats.bsdf_rays as f64 / secs / 1e6
        );
        if !args.report {
            // The light system's warnings (lights skipped, a sky at night); --report prints them in the report.
            for w in &stats.report.warnings {
                eprintln!("warning: {w}");
            }
        }
        if args.report {
            eprint!("{}", stats.report);
            let p = stats.passes;
            println!(
                "passes: camera {:.3} s, light system {:.3} s, shading and film {:.3} s",
                p.camera, p.light_system, p.shading
            );
        }
    }
    Ok(())
}

//! `kelvin bench lights`: the many-lights scaling report (table + plots).
//! `kelvin bench render`: the render suite of real glTF files (table, or JSON).

use std::path::PathBuf;

use clap::{Args, Subcommand};

use kelvin::render::job::{self, IntegratorChoice, SamplerChoice};
use kelvin::render::path::PathDepth;
use kelvin::render::renderer::Integrator;
use kelvin::report::lights::{LightBenchConfig, format_tables, run_light_bench, write_plots};
use kelvin::report::render_bench::{RenderBenchConfig, SUITE, format_table, run_render_bench, to_json};

use super::{CliError, values};

#[derive(Args)]
pub struct BenchArgs {
    #[command(subcommand)]
    what: BenchCommand,
}

#[derive(Subcommand)]
enum BenchCommand {
    /// Light samplers against the number of lights: time per sample, relative RMSE at equal
    /// time, and update time when lights move (scaling scene + emissive-panel room).
    Lights(LightsArgs),
    /// Render throughput on the suite of real glTF files (direct lighting or the path tracer, MIS,
    /// light BVH): seconds, M samples/s, M shadow rays/s and M BSDF rays/s per scene.
    Render(RenderArgs),
}

#[derive(Args)]
struct RenderArgs {
    /// Image size as WIDTHxHEIGHT.
    #[arg(long, default_value = "128x128", value_parser = values::size)]
    size: (u32, u32),
    /// Samples per pixel for every scene; default: each scene's own (about a second of rendering
    /// on a 2-core machine, the same samples per image at any size).
    #[arg(long, value_parser = values::whole(kelvin::render::job::SPP))]
    spp: Option<u32>,
    /// Scenes to run, comma-separated; default: the whole suite.
    #[arg(long, value_delimiter = ',')]
    scenes: Vec<String>,
    /// Timed renders per scene after a 1-spp warm-up; the fastest counts.
    #[arg(long, default_value_t = 3, value_parser = values::count(1..=1000))]
    repeat: usize,
    /// Folder of the real test data; default: the repository's tests/data.
    #[arg(long, default_value = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data"))]
    data: PathBuf,
    /// Worker threads (default: all cores).
    #[arg(long, value_parser = values::threads())]
    threads: Option<usize>,
    /// Direct lighting (as Mitsuba's `direct`), or the path tracer (as Mitsuba's `path`).
    #[arg(long, value_enum, default_value = "direct")]
    integrator: IntegratorChoice,
    /// With `--integrator path`: surfaces after the camera's a path may reach (Mitsuba's
    /// max_depth is one more).
    #[arg(long, default_value_t = PathDepth::DEFAULT.max_depth, value_parser = values::whole(job::DEPTH))]
    max_depth: u32,
    /// How lights are chosen per sample (RIS and ReSTIR with `kelvin render`'s default
    /// candidates and neighbours).
    #[arg(long, value_enum, default_value = "bvh")]
    light_sampler: SamplerChoice,
    /// After the table, print every row (counts, pass times, warnings) as one line of JSON.
    #[arg(long)]
    json: bool,
    /// List the suite's scenes and files, and exit.
    #[arg(long)]
    list: bool,
}

#[derive(Args)]
struct LightsArgs {
    /// Light counts of the scaling scene, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = [1usize, 10, 100, 1_000, 10_000, 100_000, 1_000_000],
        value_parser = values::count(1..=100_000_000))]
    counts: Vec<usize>,
    /// Folder for the plots (SVG); created if missing.
    #[arg(long, default_value = "bench-lights")]
    out: PathBuf,
    /// Ground points where irradiance is estimated.
    #[arg(long, default_value_t = 128, value_parser = values::count(1..=1 << 24))]
    points: usize,
    /// Samples per point for timing and the measured RMSE.
    #[arg(long, default_value_t = 512, value_parser = values::count(1..=1 << 24))]
    samples: usize,
    /// Frames per update measurement.
    #[arg(long, default_value_t = 10, value_parser = values::count(1..=100_000))]
    frames: usize,
    /// How far each moving light moves per frame, m (per horizontal axis, at most).
    #[arg(long, default_value_t = 0.25, value_parser = values::finite_in(0.0, 1e6))]
    move_step: f32,
    /// Tiles per side of the emissive panel (2 tiles^2 triangles); 0 skips the room.
    #[arg(long, default_value_t = 64, value_parser = values::count(0..=4096))]
    panel_tiles: usize,
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

/// Runs the chosen benchmark.
pub fn run(args: BenchArgs) -> Result<(), CliError> {
    match args.what {
        BenchCommand::Lights(a) => lights(a),
        BenchCommand::Render(a) => render(a),
    }
}

fn render(a: RenderArgs) -> Result<(), CliError> {
    if a.list {
        for s in SUITE {
            let env = s.env.map(|(m, x)| format!(" --env {m} --env-intensity {x}")).unwrap_or_default();
            println!("{}: {}{env}, {} spp at 128x128: {}", s.name, s.file, s.spp_128, s.about);
        }
        return Ok(());
    }
    values::data_dir(&a.data)?;
    if let Some(t) = a.threads {
        rayon::ThreadPoolBuilder::new().num_threads(t).build_global()?;
    }
    if cfg!(debug_assertions) {
        eprintln!("note: a debug build; timings are only meaningful with --release");
    }
    let cfg = RenderBenchConfig {
        data_dir: a.data,
        width: a.size.0,
        height: a.size.1,
        spp: a.spp,
        repeat: a.repeat,
        scenes: a.scenes,
        integrator: match a.integrator {
            IntegratorChoice::Direct => Integrator::Direct,
            IntegratorChoice::Path => Integrator::Path(PathDepth { max_depth: a.max_depth, ..PathDepth::DEFAULT }),
        },
        light_sampler: a.light_sampler,
    };
    let rows = run_render_bench(&cfg, |line| eprintln!("{line}")).map_err(|e| e.to_string())?;
    print!("{}", format_table(&rows));
    if a.json {
        println!("{}", to_json(&rows));
    }
    Ok(())
}

fn lights(a: LightsArgs) -> Result<(), CliError> {
    if a.counts.is_empty() || a.points == 0 || a.samples == 0 {
        return Err("--counts, --points and --samples must be non-empty and positive".into());
    }
    if cfg!(debug_assertions) {
        eprintln!("note: a debug build; timings are only meaningful with --release");
    }
    let cfg = LightBenchConfig {
        counts: a.counts,
        points: a.points,
        samples: a.samples,
        frames: a.frames,
        move_step: a.move_step,
        panel_tiles: a.panel_tiles,
        seed: a.seed,
    };
    let rows = run_light_bench(&cfg, |line| eprintln!("{line}"));
    print!("{}", format_tables(&rows, cfg.samples, cfg.move_step));
    std::fs::create_dir_all(&a.out).map_err(|e| format!("cannot create {}: {e}", a.out.display()))?;
    for path in write_plots(&rows, &a.out)? {
        println!("wrote {}", path.display());
    }
    Ok(())
}

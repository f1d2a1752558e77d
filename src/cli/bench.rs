//! `kelvin bench lights`: the many-lights scaling report (table + plots).

use std::path::PathBuf;

use clap::{Args, Subcommand};

use kelvin::report::lights::{LightBenchConfig, format_tables, run_light_bench, write_plots};

use super::CliError;

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
}

#[derive(Args)]
struct LightsArgs {
    /// Light counts of the scaling scene, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = [1usize, 10, 100, 1_000, 10_000, 100_000, 1_000_000])]
    counts: Vec<usize>,
    /// Folder for the plots (SVG); created if missing.
    #[arg(long, default_value = "bench-lights")]
    out: PathBuf,
    /// Ground points where irradiance is estimated.
    #[arg(long, default_value_t = 128)]
    points: usize,
    /// Samples per point for timing and the measured RMSE.
    #[arg(long, default_value_t = 512)]
    samples: usize,
    /// Frames per update measurement.
    #[arg(long, default_value_t = 10)]
    frames: usize,
    /// How far each moving light moves per frame, m (per horizontal axis, at most).
    #[arg(long, default_value_t = 0.25)]
    move_step: f32,
    /// Tiles per side of the emissive panel (2 tiles^2 triangles); 0 skips the room.
    #[arg(long, default_value_t = 64)]
    panel_tiles: usize,
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

/// Runs the chosen benchmark.
pub fn run(args: BenchArgs) -> Result<(), CliError> {
    match args.what {
        BenchCommand::Lights(a) => lights(a),
    }
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
        frames: a.frames.max(1),
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

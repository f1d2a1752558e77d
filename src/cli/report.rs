//! `kelvin report accuracy [SCENE...] [--out DIR] [--quick] [--data DIR] [--threads T]`.

use std::path::PathBuf;

use kelvin::report::accuracy::{AccuracyOptions, Budget, SceneId, run_accuracy};

use super::CliError;

#[derive(clap::Args)]
pub struct ReportArgs {
    #[command(subcommand)]
    report: Report,
}

#[derive(clap::Subcommand)]
enum Report {
    /// What accuracy costs in time: each knob (spp, light sampler, spectral vs RGB, env-table
    /// resolution, MIS / light-only / BSDF-only, one vs all lights, shadow-ray offsets, f32 vs f64)
    /// swept against a converged reference; CSV, Markdown tables and log-log plots.
    Accuracy(AccuracyArgs),
}

#[derive(clap::Args)]
struct AccuracyArgs {
    /// Scenes: default, many-lights, env-sun, checker-2700k, checker-f11 (all when absent).
    scenes: Vec<String>,
    /// Output folder; references are cached there.
    #[arg(long, default_value = "accuracy-report")]
    out: PathBuf,
    /// 32x32 images, 512-spp references, 8-spp baseline: under a minute.
    #[arg(long)]
    quick: bool,
    /// Folder of the real test data (for the env map); default: the repository's tests/data.
    #[arg(long, default_value = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data"))]
    data: PathBuf,
    /// Worker threads (default: all cores).
    #[arg(long, value_parser = super::values::threads())]
    threads: Option<usize>,
}

pub fn run(args: ReportArgs) -> Result<(), CliError> {
    let Report::Accuracy(args) = args.report;
    if let Some(t) = args.threads {
        rayon::ThreadPoolBuilder::new().num_threads(t).build_global()?;
    }
    let scenes = args.scenes.iter().map(|s| SceneId::parse(s)).collect::<Result<Vec<_>, _>>()?;
    let opts = AccuracyOptions {
        scenes,
        out: args.out.clone(),
        budget: if args.quick { Budget::QUICK } else { Budget::DEFAULT },
        data_dir: args.data,
    };
    let start = std::time::Instant::now();
    let reports = run_accuracy(&opts, &mut |msg| eprintln!("{msg}"))?;
    for r in &reports {
        println!(
            "{}: {} settings, MSE ~ spp^{:.2}; {}",
            r.scene.name(),
            r.rows.len(),
            r.spp_slope,
            r.files.iter().map(|f| f.display().to_string()).collect::<Vec<_>>().join(", ")
        );
    }
    println!("wrote {} in {:.1} s", args.out.join("README.md").display(), start.elapsed().as_secs_f64());
    Ok(())
}

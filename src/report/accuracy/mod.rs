//! What accuracy costs in time: `kelvin report accuracy`.
//!
//! For each scene the report renders a converged reference (or reads it from the cache), then
//! turns one knob at a time away from a baseline configuration and records, per setting, the
//! render time and samples/s, the relative MSE and maximum error against the reference and, on
//! the colour checkers, CIEDE2000 per patch. Every row is the mean over `reps` renders with
//! different seeds. A knob's settings are rendered in turn, round after round, so that they
//! share the machine's load; a row's time is its fastest render, after an untimed update that
//! rebuilds any table the setting needs (one-time builds are not counted).
//!
//! Rows of the colour knob are compared with the spectral reference (the physically right
//! answer); every other row with the reference in the baseline's colour mode, so that only the
//! knob differs. Ratios are against the knob's baseline row; "efficiency" is
//! (MSE x time) of the baseline over that of the row: above 1, the setting buys accuracy more
//! cheaply than the baseline does.

mod knobs;
mod metrics;
mod output;
mod plot;
mod reference;
mod scenes;
mod sweep;

use std::path::PathBuf;

pub use knobs::{Config, ENV_TABLE_WIDTHS, FIXED_EPSILONS, Knob};
pub use metrics::{loglog_slope, max_error, patch_de00, patch_means, rel_mse};
pub use reference::{REFERENCE_SEED, REFERENCE_VERSION, Reference};
pub use scenes::{BuiltScene, ENV_MAP, MANY_LIGHTS, SceneId};

use crate::shading::ColorMode;

/// Image size, sample counts and repetitions of a run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Budget {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Samples per pixel of the references.
    pub reference_spp: u32,
    /// Samples per pixel of the baseline every knob turns away from.
    pub base_spp: u32,
    /// End of the spp ladder (1, 2, 4, ...).
    pub max_spp: u32,
    /// Renders (seeds) per setting.
    pub reps: u32,
}

impl Budget {
    /// The default run: 64 x 64, references at 4096 spp, baseline 64 spp (under 10 minutes on 2 cores).
    pub const DEFAULT: Budget =
        Budget { width: 64, height: 64, reference_spp: 4096, base_spp: 64, max_spp: 256, reps: 4 };
    /// `--quick`: 32 x 32, references at 512 spp, baseline 8 spp (under a minute).
    pub const QUICK: Budget = Budget { width: 32, height: 32, reference_spp: 512, base_spp: 8, max_spp: 32, reps: 3 };
}

/// What to run and where to write it.
#[derive(Clone, Debug)]
pub struct AccuracyOptions {
    /// Scenes to report on (all when empty).
    pub scenes: Vec<SceneId>,
    /// Output folder (created if needed); references are cached there.
    pub out: PathBuf,
    /// Image size, sample counts and repetitions.
    pub budget: Budget,
    /// Folder of the real test data (the repository's `tests/data`); the env scene is skipped,
    /// with the reason, when its map is not there.
    pub data_dir: PathBuf,
}

/// Why the report could not be made.
#[derive(Debug, thiserror::Error)]
pub enum AccuracyError {
    /// A scene name matches none of the report's scenes.
    #[error("unknown scene '{given}'; accepted: {accepted}")]
    UnknownScene {
        /// The name given.
        given: String,
        /// The accepted names, comma-separated.
        accepted: String,
    },
    /// A folder could not be created or a file (CSV, Markdown, reference metadata) written.
    #[error("{path}: {msg}")]
    Io {
        /// The folder or file.
        path: String,
        /// The system's error message.
        msg: String,
    },
    /// A reference image could not be written.
    #[error(transparent)]
    ImageOut(#[from] crate::render::film_io::ImageIoError),
    /// A scene's environment map could not be read.
    #[error(transparent)]
    ImageIn(#[from] crate::scene::image::ImageError),
    /// A plot could not be drawn or written.
    #[error(transparent)]
    Plot(#[from] crate::report::plot::PlotError),
}

/// Which reference a row is compared with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Against {
    /// The reference in the baseline's colour mode.
    Main,
    /// The spectral reference (colour-knob rows of RGB-baseline scenes).
    Spectral,
}

/// One setting of one knob, measured.
#[derive(Clone, Debug)]
pub struct Row {
    /// The knob turned.
    pub knob: Knob,
    /// The setting's label, as in tables and plots.
    pub setting: String,
    /// The whole configuration rendered.
    pub config: Config,
    /// Fastest render of the setting, s.
    pub seconds: f64,
    /// `time_ratio` times the spp knob's baseline time, s: the time on a common footing, since
    /// the machine's load may drift between knobs (each knob re-times its own baseline). The
    /// plots and the Pareto front use it.
    pub norm_seconds: f64,
    /// Camera samples per second of that render.
    pub samples_per_s: f64,
    /// Mean over the renders of [`rel_mse`] and [`max_error`].
    pub rel_mse: f64,
    /// Mean over the renders of [`max_error`].
    pub max_err: f64,
    /// Estimated squared bias in relative-MSE units, the error left at infinite spp, and its
    /// standard error. From the n renders' mean image, whose MSE is bias^2 + variance / n, and
    /// their mean MSE, bias^2 + variance: (n MSE(mean) - mean MSE) / (n - 1). It includes the
    /// reference's own noise (about the baseline's relative MSE x base spp / reference spp); NaN
    /// for one render.
    pub bias2: f64,
    /// Standard error of `bias2`.
    pub bias2_se: f64,
    /// Mean and max CIEDE2000 over the colour-checker patches (checker scenes only).
    pub de00: Option<(f64, f64)>,
    /// Which reference the row is compared with.
    pub against: Against,
    /// This is the knob's baseline setting.
    pub baseline: bool,
    /// Time, relative MSE and efficiency against the knob's baseline row.
    pub time_ratio: f64,
    /// Relative MSE over the baseline's.
    pub error_ratio: f64,
    /// (relative MSE x time) of the baseline over the row's: above 1, a cheaper way to accuracy.
    pub efficiency: f64,
    /// On the Pareto front of (`norm_seconds`, relative MSE) among the rows compared with the main
    /// reference.
    pub pareto: bool,
}

/// The report of one scene.
#[derive(Clone, Debug)]
pub struct SceneReport {
    /// The scene reported on.
    pub scene: SceneId,
    /// The budget it was run with.
    pub budget: Budget,
    /// Number of lights in the scene.
    pub n_lights: usize,
    /// One row per setting of each of the scene's knobs, knob by knob.
    pub rows: Vec<Row>,
    /// The main reference against itself: must be all zeros.
    pub self_check: Row,
    /// The main reference (in the baseline's colour mode), then the spectral one when the colour
    /// knob needs it.
    pub references: Vec<Reference>,
    /// Slope of log relative MSE against log spp on the spp ladder (about -1 for an unbiased
    /// estimator with independent numbers, steeper where the Sobol pattern stratifies smooth light).
    pub spp_slope: f64,
    /// Files written: CSV, Markdown, plot.
    pub files: Vec<PathBuf>,
}

/// Runs the report on one built scene and writes its files.
pub fn report_scene(
    scene: &mut BuiltScene,
    opts: &AccuracyOptions,
    progress: &mut dyn FnMut(&str),
) -> Result<SceneReport, AccuracyError> {
    let budget = opts.budget;
    let (w, h) = (budget.width, budget.height);
    let knobs = scene.id.knobs();
    // kelvin's defaults (the light-BVH sampler among them) in the scene's colour mode.
    let base = Config::baseline(budget.base_spp, scene.id.baseline_color());
    let main_ref_config = Config { spp: budget.reference_spp, ..base };
    let main_ref = reference::reference(scene, &main_ref_config, w, h, &opts.out, progress)?;
    let mut references = vec![main_ref];
    if base.color != ColorMode::Spectral && knobs.contains(&Knob::Color) {
        let c = Config { color: ColorMode::Spectral, ..main_ref_config };
        references.push(reference::reference(scene, &c, w, h, &opts.out, progress)?);
    }

    let mut rows = Vec::new();
    for &knob in &knobs {
        let settings = knob.settings(&base, budget.max_spp, scene.n_lights);
        progress(&format!("  {} ({} settings)", knob.name(), settings.len()));
        let configs: Vec<Config> = settings.iter().map(|s| s.1).collect();
        let renders = sweep::render_knob(scene, &configs, &budget);
        let against = if knob == Knob::Color && references.len() > 1 { Against::Spectral } else { Against::Main };
        let reference = &references[if against == Against::Spectral { 1 } else { 0 }];
        for ((label, _), r) in settings.into_iter().zip(&renders) {
            rows.push(sweep::measure(knob, label, r, reference, against, scene, &budget));
        }
    }
    sweep::finish_rows(&mut rows, &base);

    let main = &references[0];
    let itself = sweep::Renders {
        config: main_ref_config,
        images: vec![main.pixels.clone()],
        seconds: main.seconds,
        samples: 0,
    };
    let mut self_check =
        sweep::measure(Knob::Spp, "reference itself".into(), &itself, main, Against::Main, scene, &budget);
    self_check.samples_per_s = w as f64 * h as f64 * main.spp as f64 / main.seconds.max(1e-9);
    let ladder: Vec<(f64, f64)> =
        rows.iter().filter(|r| r.knob == Knob::Spp).map(|r| (r.config.spp as f64, r.rel_mse)).collect();
    let mut report = SceneReport {
        scene: scene.id,
        budget,
        n_lights: scene.n_lights,
        rows,
        self_check,
        references,
        spp_slope: loglog_slope(&ladder),
        files: Vec::new(),
    };
    report.files = output::write_scene(&report, &opts.out)?;
    Ok(report)
}

/// Runs the report over `opts.scenes` (all when empty), writing per-scene CSV, Markdown and plot
/// files and a `README.md` index into `opts.out`. Scenes whose data is missing are skipped with
/// a message through `progress`.
pub fn run_accuracy(opts: &AccuracyOptions, progress: &mut dyn FnMut(&str)) -> Result<Vec<SceneReport>, AccuracyError> {
    std::fs::create_dir_all(&opts.out)
        .map_err(|e| AccuracyError::Io { path: opts.out.display().to_string(), msg: e.to_string() })?;
    let ids = if opts.scenes.is_empty() { SceneId::ALL.to_vec() } else { opts.scenes.clone() };
    let mut reports = Vec::new();
    for id in ids {
        progress(&format!("scene {}", id.name()));
        let start = std::time::Instant::now();
        match scenes::build(id, &opts.data_dir)? {
            Ok(mut scene) => {
                reports.push(report_scene(&mut scene, opts, progress)?);
                progress(&format!("  done in {:.1} s", start.elapsed().as_secs_f64()));
            }
            Err(why) => progress(&format!("  skipped: {why}")),
        }
    }
    output::write_index(&reports, &opts.out)?;
    Ok(reports)
}

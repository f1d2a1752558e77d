//! The report's files: per scene a CSV (every number), a Markdown table and an SVG plot; and a
//! `README.md` index with every table.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::{AccuracyError, Against, Row, SceneReport};
use crate::geometry::ShadowOffset;

fn write(path: &Path, text: &str) -> Result<(), AccuracyError> {
    std::fs::write(path, text).map_err(|e| AccuracyError::Io { path: path.display().to_string(), msg: e.to_string() })
}

/// Writes `<scene>.csv`, `<scene>.md` and `<scene>-error-vs-time.svg` (and `.png`) into `out`.
pub fn write_scene(report: &SceneReport, out: &Path) -> Result<Vec<PathBuf>, AccuracyError> {
    let name = report.scene.name();
    let csv = out.join(format!("{name}.csv"));
    write(&csv, &csv_text(report))?;
    let md = out.join(format!("{name}.md"));
    write(&md, &markdown(report))?;
    let svg = out.join(format!("{name}-error-vs-time.svg"));
    super::plot::error_vs_time(&svg, report)?;
    let png = svg.with_extension("png");
    super::plot::error_vs_time(&png, report)?;
    Ok(vec![csv, md, svg, png])
}

/// Writes `README.md`: how the run was made and every scene's table and plot.
pub fn write_index(reports: &[SceneReport], out: &Path) -> Result<(), AccuracyError> {
    let mut s = String::from("# What accuracy costs in time\n\n");
    s += "Made by `kelvin report accuracy`; see `src/report/accuracy/mod.rs` for what each column means.\n\n";
    for r in reports {
        let _ = writeln!(s, "![{0}]({0}-error-vs-time.svg)\n", r.scene.name());
        s += &markdown(r);
        s += "\n";
    }
    write(&out.join("README.md"), &s)
}

const CSV_HEADER: &str = "scene,knob,setting,spp,color,sampler,selection,strategy,shadow_offset,light_math,env_table,\
against,seconds,norm_seconds,samples_per_s,rel_mse,max_err,bias2,bias2_se,de00_mean,de00_max,time_ratio,error_ratio,efficiency,baseline,pareto";

fn csv_row(scene: &str, knob: &str, r: &Row) -> String {
    let c = &r.config;
    let offset = match c.offset {
        ShadowOffset::ErrorBound => "error-bound".to_string(),
        ShadowOffset::FixedEpsilon(e) => format!("fixed-{e:e}"),
    };
    let env = c.env_table_width.map_or("full".to_string(), |w| w.to_string());
    let (de_mean, de_max) =
        r.de00.map_or((String::new(), String::new()), |(a, b)| (format!("{a:.6}"), format!("{b:.6}")));
    format!(
        "{scene},{knob},{},{},{:?},{:?},{:?},{:?},{offset},{:?},{env},{:?},{:.6},{:.6},{:.1},{:.6e},{:.6e},{:.6e},{:.6e},{de_mean},{de_max},{:.4},{:.4},{:.4},{},{}",
        r.setting.replace(',', ";"),
        c.spp,
        c.color,
        c.sampler,
        c.selection,
        c.strategy,
        c.precision,
        r.against,
        r.seconds,
        r.norm_seconds,
        r.samples_per_s,
        r.rel_mse,
        r.max_err,
        r.bias2,
        r.bias2_se,
        r.time_ratio,
        r.error_ratio,
        r.efficiency,
        r.baseline,
        r.pareto
    )
}

/// Every row, then the reference against itself (knob "reference").
pub fn csv_text(report: &SceneReport) -> String {
    let name = report.scene.name();
    let mut s = format!("{CSV_HEADER}\n");
    for r in &report.rows {
        s += &csv_row(name, r.knob.name(), r);
        s.push('\n');
    }
    s += &csv_row(name, "reference", &report.self_check);
    s.push('\n');
    s
}

/// The scene's table, with a header saying how it was made.
pub fn markdown(report: &SceneReport) -> String {
    let b = report.budget;
    let mut s = format!("## {}\n\n", report.scene.name());
    let refs: Vec<String> = report
        .references
        .iter()
        .map(|r| {
            let cached = if r.cached { ", cached" } else { "" };
            format!("{:?} at {} spp ({:.1} s{cached})", r.color, r.spp, r.seconds)
        })
        .collect();
    let _ = writeln!(
        s,
        "{}x{} pixels, {} lights; references: {}. Baseline: {:?}, {} sampler, one light per sample, MIS, \
         error-bound offsets, f32, {} spp; {} renders per setting. Relative MSE falls as spp^{:.2} on the spp ladder; \
         the reference against itself: relative MSE {}, max error {}.\n",
        b.width,
        b.height,
        report.n_lights,
        refs.join(", "),
        report.rows.first().map(|r| r.config.color).unwrap_or_default(),
        format!("{:?}", report.rows.first().map(|r| r.config.sampler).unwrap_or_default()).to_lowercase(),
        b.base_spp,
        b.reps,
        report.spp_slope,
        report.self_check.rel_mse,
        report.self_check.max_err,
    );
    let checker = report.rows.iter().any(|r| r.de00.is_some());
    s += "| knob | setting | spp | time (ms) | Msamples/s | rel. MSE | max err | bias^2 | time x | MSE x | efficiency x |";
    s += if checker { " dE00 mean | dE00 max |\n" } else { "\n" };
    s += "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|";
    s += if checker { "---:|---:|\n" } else { "\n" };
    for r in &report.rows {
        let mut setting = r.setting.clone();
        if r.baseline {
            setting += " (base)";
        }
        if r.pareto {
            setting += " \\*";
        }
        if r.against == Against::Spectral {
            setting += " vs spectral ref.";
        }
        let _ = write!(
            s,
            "| {} | {setting} | {} | {:.1} | {:.2} | {:.3e} | {:.3} | {} | {:.2} | {:.3} | {:.2} |",
            r.knob.name(),
            r.config.spp,
            r.seconds * 1e3,
            r.samples_per_s / 1e6,
            r.rel_mse,
            r.max_err,
            if r.bias2 > 2.0 * r.bias2_se { format!("{:.1e}", r.bias2) } else { "~0".to_string() },
            r.time_ratio,
            r.error_ratio,
            r.efficiency
        );
        match r.de00 {
            Some((m, x)) => {
                let _ = writeln!(s, " {m:.2} | {x:.2} |");
            }
            None => s.push('\n'),
        }
    }
    s += "\n(base): the knob's baseline. \\*: on the Pareto front of relative MSE and time (each knob is timed \
          against its own baseline run, then scaled to the spp baseline). bias^2: the relative MSE left at infinite \
          spp, estimated from the renders' spread (~0: below two standard errors; its floor is the reference's own \
          noise). Ratios are against the knob's baseline; efficiency x = (MSE x time of the baseline) / (MSE x time).\n";
    s
}

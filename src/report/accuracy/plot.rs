//! The report's plot: relative MSE against render time, log-log, one curve per knob (its
//! settings in order, all through the baseline), the Pareto front as a dashed black line. The
//! left panel shows every row; the right one zooms on the baseline (spp within 4x of it) and
//! names the settings.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{Against, Knob, Row, SceneReport};
use crate::report::plot::{PALETTE, PlotError};

/// Draws `report` into `path`, an .svg or a .png.
pub fn error_vs_time(path: &Path, report: &SceneReport) -> Result<(), PlotError> {
    crate::report::plot::register_font();
    let err = |e: String| PlotError { path: path.display().to_string(), msg: e };
    let size = (1280, 560);
    match path.extension().and_then(|e| e.to_str()) {
        Some("png") => crate::report::plot::png_plot(path, size, |area| draw(area, report)).map_err(err),
        _ => draw(SVGBackend::new(path, size).into_drawing_area(), report).map_err(err),
    }
}

/// (normalised time in ms, relative MSE) of a row, if it fits a log axis.
fn point(r: &Row) -> Option<(f64, f64)> {
    let p = (r.norm_seconds * 1e3, r.rel_mse);
    (p.0 > 0.0 && p.1 > 0.0 && p.0.is_finite() && p.1.is_finite()).then_some(p)
}

fn draw<DB: DrawingBackend>(area: DrawingArea<DB, Shift>, report: &SceneReport) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let e = |x: &dyn std::fmt::Display| x.to_string();
    area.fill(&WHITE).map_err(|x| e(&x))?;
    let b = report.budget;
    let title = format!(
        "{}: relative MSE vs render time ({}x{}, baseline {} spp, {} lights)",
        report.scene.name(),
        b.width,
        b.height,
        b.base_spp,
        report.n_lights
    );
    let area = area.titled(&title, ("sans-serif", 20)).map_err(|x| e(&x))?;
    let (left, right) = area.split_horizontally(560);
    panel(&left, report, false).map_err(|x| e(&x))?;
    panel(&right, report, true).map_err(|x| e(&x))?;
    area.present().map_err(|x| e(&x))?;
    Ok(())
}

/// One panel; `zoom` keeps spp rows within 4x of the baseline and labels every setting.
fn panel<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, report: &SceneReport, zoom: bool) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let e = |x: &dyn std::fmt::Display| x.to_string();
    let base_spp = report.budget.base_spp;
    let shown =
        |r: &Row| !zoom || r.knob != Knob::Spp || (r.config.spp * 4 >= base_spp && r.config.spp <= 4 * base_spp);
    let rows: Vec<&Row> = report.rows.iter().filter(|r| shown(r) && point(r).is_some()).collect();
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for (x, y) in rows.iter().filter_map(|r| point(r)) {
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
    }
    if rows.is_empty() {
        (x0, x1, y0, y1) = (1.0, 10.0, 1e-3, 1.0);
    }
    let caption = if zoom { "around the baseline" } else { "every setting" };
    let mut chart = ChartBuilder::on(area)
        .caption(caption, ("sans-serif", 15))
        .margin(10)
        .x_label_area_size(36)
        .y_label_area_size(60)
        .build_cartesian_2d((x0 / 1.25..x1 * 1.6).log_scale(), (y0 / 1.6..y1 * 1.6).log_scale())
        .map_err(|x| e(&x))?;
    chart
        .configure_mesh()
        .x_desc("render time (ms; ratio to the knob's baseline x the spp baseline's time)")
        .y_desc("relative MSE")
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .x_label_formatter(&|v| format!("{v:.0}"))
        .draw()
        .map_err(|x| e(&x))?;
    let knobs: Vec<Knob> = Knob::ALL.into_iter().filter(|k| report.rows.iter().any(|r| r.knob == *k)).collect();
    for (i, knob) in knobs.iter().enumerate() {
        let color = PALETTE[i % PALETTE.len()];
        let mine: Vec<&Row> = rows.iter().copied().filter(|r| r.knob == *knob).collect();
        let curve: Vec<(f64, f64)> = mine.iter().filter_map(|r| point(r)).collect();
        let name = if mine.first().map(|r| r.against) == Some(Against::Spectral) {
            format!("{} (vs spectral ref.)", knob.name())
        } else {
            knob.name().to_string()
        };
        chart
            .draw_series(LineSeries::new(curve.clone(), color.stroke_width(2)))
            .map_err(|x| e(&x))?
            .label(name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2)));
        chart.draw_series(curve.iter().map(|&p| Circle::new(p, 3, color.filled()))).map_err(|x| e(&x))?;
        if zoom {
            let style = ("sans-serif", 11).into_font().color(&color);
            let labels = mine.iter().filter(|r| !r.baseline || *knob == Knob::Spp).filter_map(|r| {
                let text = if r.baseline { format!("{} (base)", r.setting) } else { r.setting.clone() };
                point(r).map(|p| EmptyElement::at(p) + Text::new(text, (5, -12), style.clone()))
            });
            chart.draw_series(labels).map_err(|x| e(&x))?;
        }
    }
    let mut front: Vec<(f64, f64)> = rows.iter().filter(|r| r.pareto).filter_map(|r| point(r)).collect();
    front.sort_by(|a, b| a.0.total_cmp(&b.0));
    chart
        .draw_series(DashedLineSeries::new(front.clone(), 6, 4, BLACK.stroke_width(1)))
        .map_err(|x| e(&x))?
        .label("Pareto front")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], BLACK.stroke_width(1)));
    chart.draw_series(front.iter().map(|&p| Circle::new(p, 6, BLACK.stroke_width(1)))).map_err(|x| e(&x))?;
    if !zoom {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 12))
            .draw()
            .map_err(|x| e(&x))?;
    }
    Ok(())
}

//! The report's plot: relative MSE against render time, log-log, one curve per knob (its
//! settings in order, all through the baseline), the Pareto front as a dashed black line.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{Against, Knob, SceneReport};
use crate::report::plot::PlotError;

const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];

/// Draws `report` into `path`, an .svg or a .png.
pub fn error_vs_time(path: &Path, report: &SceneReport) -> Result<(), PlotError> {
    crate::report::plot::register_font();
    let err = |e: String| PlotError { path: path.display().to_string(), msg: e };
    let size = (900, 600);
    match path.extension().and_then(|e| e.to_str()) {
        Some("png") => draw(BitMapBackend::new(path, size).into_drawing_area(), report).map_err(err),
        _ => draw(SVGBackend::new(path, size).into_drawing_area(), report).map_err(err),
    }
}

fn draw<DB: DrawingBackend>(area: DrawingArea<DB, Shift>, report: &SceneReport) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let e = |x: &dyn std::fmt::Display| x.to_string();
    area.fill(&WHITE).map_err(|x| e(&x))?;
    // Time in ms; only positive values fit a log axis.
    let pts: Vec<(f64, f64)> = report
        .rows
        .iter()
        .map(|r| (r.seconds * 1e3, r.rel_mse))
        .filter(|p| p.0 > 0.0 && p.1 > 0.0 && p.0.is_finite() && p.1.is_finite())
        .collect();
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(x, y) in &pts {
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
    }
    if pts.is_empty() {
        (x0, x1, y0, y1) = (1.0, 10.0, 1e-3, 1.0);
    }
    let b = report.budget;
    let title = format!(
        "{}: relative MSE vs time ({}x{}, baseline {} spp)",
        report.scene.name(),
        b.width,
        b.height,
        b.base_spp
    );
    let mut chart = ChartBuilder::on(&area)
        .caption(title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d((x0 / 1.3..x1 * 1.3).log_scale(), (y0 / 2.0..y1 * 2.0).log_scale())
        .map_err(|x| e(&x))?;
    chart
        .configure_mesh()
        .x_desc("render time (ms)")
        .y_desc("relative MSE")
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .draw()
        .map_err(|x| e(&x))?;
    let knobs: Vec<Knob> = Knob::ALL.into_iter().filter(|k| report.rows.iter().any(|r| r.knob == *k)).collect();
    for (i, knob) in knobs.iter().enumerate() {
        let color = PALETTE[i % PALETTE.len()];
        let curve: Vec<(f64, f64)> = report
            .rows
            .iter()
            .filter(|r| r.knob == *knob && r.seconds > 0.0 && r.rel_mse > 0.0)
            .map(|r| (r.seconds * 1e3, r.rel_mse))
            .collect();
        let against = report.rows.iter().find(|r| r.knob == *knob).map(|r| r.against);
        let name = if against == Some(Against::Spectral) {
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
        // Name the settings of every knob but the (self-explaining) spp ladder.
        if *knob != Knob::Spp {
            let labels =
                report.rows.iter().filter(|r| r.knob == *knob && !r.baseline && r.seconds > 0.0 && r.rel_mse > 0.0);
            chart
                .draw_series(labels.map(|r| {
                    Text::new(
                        r.setting.clone(),
                        (r.seconds * 1e3, r.rel_mse),
                        ("sans-serif", 11).into_font().color(&color),
                    )
                }))
                .map_err(|x| e(&x))?;
        }
    }
    let mut front: Vec<(f64, f64)> =
        report.rows.iter().filter(|r| r.pareto && r.rel_mse > 0.0).map(|r| (r.seconds * 1e3, r.rel_mse)).collect();
    front.sort_by(|a, b| a.0.total_cmp(&b.0));
    chart
        .draw_series(DashedLineSeries::new(front.clone(), 6, 4, BLACK.stroke_width(1)))
        .map_err(|x| e(&x))?
        .label("Pareto front")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], BLACK.stroke_width(1)));
    chart.draw_series(front.iter().map(|&p| Circle::new(p, 6, BLACK.stroke_width(1)))).map_err(|x| e(&x))?;
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(|x| e(&x))?;
    area.present().map_err(|x| e(&x))?;
    Ok(())
}

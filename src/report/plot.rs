//! Line plots written as SVG or PNG (chosen by the file extension), through plotters.

use std::path::Path;
use std::sync::Once;

use plotters::coord::Shift;
use plotters::prelude::*;

/// One named curve of (x, y) points.
pub struct Series {
    /// Legend label; empty for none.
    pub name: String,
    /// The points in drawing order; non-finite ones are left out.
    pub points: Vec<(f64, f64)>,
}

/// Axes and title of a plot.
pub struct PlotSpec<'a> {
    /// Caption above the chart.
    pub title: &'a str,
    /// Label of the horizontal axis.
    pub x_label: &'a str,
    /// Label of the vertical axis.
    pub y_label: &'a str,
    /// Draw with equal units on both axes (polar plots).
    pub equal_aspect: bool,
}

/// Errors writing a plot: the path and what failed.
#[derive(Debug, thiserror::Error)]
#[error("cannot write plot {path}: {msg}")]
pub struct PlotError {
    /// The plot file.
    pub path: String,
    /// What failed: an unsupported extension or plotters' error.
    pub msg: String,
}

/// Series colours of every report plot (matplotlib's "tab10" order).
pub(crate) const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];

/// Registers the bundled font under "sans-serif" (once).
pub(crate) fn register_font() {
    static ONCE: Once = Once::new();
    // DejaVu Sans (Bitstream Vera license, see fonts/LICENSE-DejaVu.txt) so PNGs need no system font.
    ONCE.call_once(|| {
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, include_bytes!("fonts/DejaVuSans.ttf"));
    });
}

/// Draws `series` as lines into `path` (.svg or .png).
pub fn line_plot(path: &Path, spec: &PlotSpec, series: &[Series]) -> Result<(), PlotError> {
    register_font();
    let err = |e: String| PlotError { path: path.display().to_string(), msg: e };
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    let size = if spec.equal_aspect { (720, 720) } else { (960, 600) };
    match ext.as_str() {
        "svg" => draw(SVGBackend::new(path, size).into_drawing_area(), spec, series).map_err(err),
        "png" => png_plot(path, size, |area| draw(area, spec, series)).map_err(err),
        _ => Err(err(format!("unsupported extension '{ext}'; use .svg or .png"))),
    }
}

/// Draws a plot of `size` pixels into a buffer and writes it to `path` as a PNG through the `image`
/// crate the renderer already uses (plotters' own PNG encoder would build a second, older `image`).
pub(crate) fn png_plot(
    path: &Path,
    size: (u32, u32),
    draw: impl FnOnce(DrawingArea<BitMapBackend<'_>, Shift>) -> Result<(), String>,
) -> Result<(), String> {
    let mut rgb = vec![0u8; size.0 as usize * size.1 as usize * 3];
    {
        let area = BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area();
        draw(area.clone())?;
        area.present().map_err(|e| e.to_string())?;
    }
    image::save_buffer_with_format(path, &rgb, size.0, size.1, image::ExtendedColorType::Rgb8, image::ImageFormat::Png)
        .map_err(|e| e.to_string())
}

fn draw<DB: DrawingBackend>(area: DrawingArea<DB, Shift>, spec: &PlotSpec, series: &[Series]) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let e = |x: &dyn std::fmt::Display| x.to_string();
    area.fill(&WHITE).map_err(|x| e(&x))?;
    let pts = series.iter().flat_map(|s| s.points.iter()).filter(|p| p.0.is_finite() && p.1.is_finite());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(x, y) in pts {
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
    }
    if x0 > x1 {
        (x0, x1, y0, y1) = (0.0, 1.0, 0.0, 1.0);
    }
    if spec.equal_aspect {
        let r = (x1 - x0).max(y1 - y0) * 0.5;
        let (cx, cy) = ((x0 + x1) * 0.5, (y0 + y1) * 0.5);
        (x0, x1, y0, y1) = (cx - r, cx + r, cy - r, cy + r);
    }
    let pad = |a: f64, b: f64| if b > a { (b - a) * 0.03 } else { 1.0 };
    let (px, py) = (pad(x0, x1), pad(y0, y1));
    let mut chart = ChartBuilder::on(&area)
        .caption(spec.title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(x0 - px..x1 + px, y0 - py..y1 + py)
        .map_err(|x| e(&x))?;
    chart.configure_mesh().x_desc(spec.x_label).y_desc(spec.y_label).draw().map_err(|x| e(&x))?;
    for (i, s) in series.iter().enumerate() {
        let color = PALETTE[i % PALETTE.len()];
        let pts = s.points.iter().copied().filter(|p| p.0.is_finite() && p.1.is_finite());
        chart
            .draw_series(LineSeries::new(pts, color.stroke_width(2)))
            .map_err(|x| e(&x))?
            .label(s.name.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2)));
    }
    if series.len() > 1 || series.iter().any(|s| !s.name.is_empty()) {
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(|x| e(&x))?;
    }
    area.present().map_err(|x| e(&x))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A PNG plot is written through the renderer's own `image` crate: the file decodes at the
    /// plot's size, the background is white and the first series is drawn in the palette's first
    /// colour.
    #[test]
    fn png_plot_decodes_with_its_curve() {
        let path = std::env::temp_dir().join(format!("kelvin-plot-{}.png", std::process::id()));
        let series = [Series { name: "line".into(), points: (0..50).map(|i| (i as f64, (i * i) as f64)).collect() }];
        let spec = PlotSpec { title: "t", x_label: "x", y_label: "y", equal_aspect: false };
        line_plot(&path, &spec, &series).unwrap();
        let image = image::open(&path).unwrap().to_rgb8();
        std::fs::remove_file(&path).unwrap();
        assert_eq!(image.dimensions(), (960, 600));
        assert_eq!(image.get_pixel(2, 2).0, [255, 255, 255]);
        let RGBColor(r, g, b) = PALETTE[0];
        assert!(image.pixels().filter(|p| p.0 == [r, g, b]).count() > 100, "the curve is drawn");
        let bad = line_plot(&path.with_extension("gif"), &spec, &series).unwrap_err();
        assert!(bad.to_string().contains("unsupported extension"), "{bad}");
    }
}

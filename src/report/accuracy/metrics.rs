//! Image error against a reference: relative MSE, maximum error, CIEDE2000 per colour patch, and
//! the log-log slope of a convergence curve.

use glam::{DVec3, Vec3};

use crate::scene::image::LUMINANCE_WEIGHTS;
use crate::scenes::color_checker::ColorChecker;
use crate::spectrum::color::srgb_to_xyz;
use crate::spectrum::lab::{ciede2000, d65_white, xyz_to_lab};

/// Relative MSE: the squared error summed over pixels and channels, over the reference's sum of
/// squares. Scale-free, and for an unbiased estimator it falls as 1/spp. 0 for identical images.
pub fn rel_mse(image: &[Vec3], reference: &[Vec3]) -> f64 {
    let (mut err, mut norm) = (0.0f64, 0.0f64);
    for (a, r) in image.iter().zip(reference) {
        let (a, r) = (a.as_dvec3(), r.as_dvec3());
        err += (a - r).length_squared();
        norm += r.length_squared();
    }
    if norm > 0.0 { err / norm } else { err }
}

/// Largest per-pixel luminance error over the reference's mean luminance.
pub fn max_error(image: &[Vec3], reference: &[Vec3]) -> f64 {
    let lum = |c: &Vec3| c.dot(LUMINANCE_WEIGHTS) as f64;
    let mean = reference.iter().map(lum).sum::<f64>() / reference.len().max(1) as f64;
    let worst = image.iter().zip(reference).map(|(a, r)| (lum(a) - lum(r)).abs()).fold(0.0, f64::max);
    if mean > 0.0 { worst / mean } else { worst }
}

/// Mean linear sRGB of every patch of `checker` (its central pixels) in a `width` x `height` image.
pub fn patch_means(image: &[Vec3], checker: &ColorChecker, width: u32, height: u32) -> Vec<DVec3> {
    (0..checker.patches.len())
        .map(|i| {
            let ([x0, x1], [y0, y1]) = checker.patch_pixels(i, width, height);
            let mut sum = DVec3::ZERO;
            for y in y0..y1 {
                for x in x0..x1 {
                    sum += image[(y * width + x) as usize].as_dvec3();
                }
            }
            sum / ((x1 - x0) * (y1 - y0)) as f64
        })
        .collect()
}

/// CIEDE2000 between each patch of `image` and of `reference` in CIELAB with the D65 white at the
/// luminance of a perfect white diffuser on the chart; returns (mean, max) over the patches.
pub fn patch_de00(image: &[Vec3], reference: &[Vec3], checker: &ColorChecker, width: u32, height: u32) -> (f64, f64) {
    let white = d65_white() * checker.white_luminance as f64;
    let lab = |rgb: DVec3| xyz_to_lab(srgb_to_xyz(rgb), white);
    let a = patch_means(image, checker, width, height);
    let r = patch_means(reference, checker, width, height);
    let de: Vec<f64> = a.iter().zip(&r).map(|(a, r)| ciede2000(lab(*a), lab(*r))).collect();
    (de.iter().sum::<f64>() / de.len().max(1) as f64, de.iter().copied().fold(0.0, f64::max))
}

/// Least-squares slope of log(y) against log(x) over the points with positive coordinates
/// (NaN with fewer than two).
pub fn loglog_slope(points: &[(f64, f64)]) -> f64 {
    let logs: Vec<(f64, f64)> =
        points.iter().filter(|(x, y)| *x > 0.0 && *y > 0.0).map(|(x, y)| (x.ln(), y.ln())).collect();
    let n = logs.len() as f64;
    if logs.len() < 2 {
        return f64::NAN;
    }
    let (mx, my) = (logs.iter().map(|p| p.0).sum::<f64>() / n, logs.iter().map(|p| p.1).sum::<f64>() / n);
    let sxy: f64 = logs.iter().map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = logs.iter().map(|(x, _)| (x - mx) * (x - mx)).sum();
    sxy / sxx
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_images_have_zero_error_and_a_scaled_one_has_the_expected_error() {
        let r: Vec<Vec3> = (0..16).map(|i| Vec3::new(i as f32, 1.0, 2.0)).collect();
        assert_eq!(rel_mse(&r, &r), 0.0);
        assert_eq!(max_error(&r, &r), 0.0);
        let a: Vec<Vec3> = r.iter().map(|c| *c * 1.1).collect();
        assert!((rel_mse(&a, &r) - 0.01).abs() < 1e-6);
    }

    #[test]
    fn slope_of_a_power_law_is_its_exponent() {
        let pts: Vec<(f64, f64)> = (0..6).map(|k| (2f64.powi(k), 3.0 * 2f64.powi(k).powf(-1.0))).collect();
        assert!((loglog_slope(&pts) + 1.0).abs() < 1e-12);
    }
}

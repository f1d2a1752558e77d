//! Projection light: phi vs Monte Carlo, pdfs, irradiance, hard cases.

use std::f32::consts::PI;
use std::sync::Arc;

use glam::{Vec2, Vec3};
use kelvin::geometry::Transform;
use kelvin::light::{
    Amount, ColorQuery, LightError, LightSampleContext, PointLight, ProjectionLight, ResolvedProjection,
};
use kelvin::rng::SplitMix64;
use kelvin::sampling::sample_uniform_sphere;
use kelvin::scene::image::{LUMINANCE_WEIGHTS, RgbImage};
use kelvin::spectrum::{SampledWavelengths, Spectrum};

use crate::common::*;

/// A 48 x 32 test picture: gradients, a checkerboard in blue and some black texels.
fn synthetic_image(width: usize, height: usize) -> RgbImage {
    let pixels = (0..height)
        .flat_map(|y| (0..width).map(move |x| (x, y)))
        .map(|(x, y)| {
            if (x * 7 + y * 3) % 11 == 0 {
                return Vec3::ZERO;
            }
            let checker = ((x / 6 + y / 6) % 2) as f32;
            Vec3::new(0.3 + 0.7 * x as f32 / width as f32, 0.5 + 0.5 * (0.4 * y as f32).sin(), 0.1 + 0.8 * checker)
        })
        .collect();
    RgbImage { width, height, pixels }
}

fn projector(image: RgbImage, fov_deg: f32, amount: Amount) -> ResolvedProjection {
    projector_at(image, fov_deg, amount, &tilted_transform())
}

fn projector_at(image: RgbImage, fov_deg: f32, amount: Amount, transform: &Transform) -> ResolvedProjection {
    let light = ProjectionLight { amount, ..ProjectionLight::new(Arc::new(image), fov_deg.to_radians()) };
    light.resolve(transform).expect("valid projection light")
}

/// Whether world direction `w` from the projector crosses the image within 1e-4 texel of an edge.
fn projection_edge(light: &ResolvedProjection) -> impl Fn(Vec3) -> bool + '_ {
    move |w| {
        let l = light.rotation.inverse() * w;
        let p = Vec2::new(l.x, l.y) / -l.z;
        let uv = Vec2::new(0.5 * (1.0 + p.x / light.half_extent.x), 0.5 * (1.0 - p.y / light.half_extent.y));
        near_grid_edge(uv, light.image.width, light.image.height, 1e-4)
    }
}

/// (a), (b), (c) for one projector: phi against importance-sampled and uniform Monte Carlo, sample
/// pdfs against `pdf_dir`, and the pdf's integral.
fn check_projection(test: &str, light: &ResolvedProjection, seed: u64) {
    let phi = light.phi() as f64;
    let importance = estimate(seed, |u| {
        light.sample_direction(u).map_or(0.0, |(w, pdf)| light.intensity_toward(w) as f64 / pdf as f64)
    });
    check_mc(test, "phi vs importance-sampled MC", importance, phi, 1e-3);
    let uniform = estimate(seed + 1, |u| light.intensity_toward(sample_uniform_sphere(u)) as f64 * 4.0 * PI as f64);
    check_mc(test, "phi vs uniform-sphere MC", uniform, phi, UNIFORM_TOL);
    check_pdf_agreement(test, seed + 2, |u| light.sample_direction(u), |w| light.pdf_dir(w), projection_edge(light));
    let integral = estimate(seed + 3, |u| light.pdf_dir(sample_uniform_sphere(u)) as f64 * 4.0 * PI as f64);
    check_mc(test, "integral of pdf_dir over the sphere", integral, 1.0, UNIFORM_TOL);
}

#[test]
fn projection_phi_matches_monte_carlo_and_pdfs_agree() {
    let light = projector(synthetic_image(48, 32), 60.0, Amount::Candela(250.0));
    check_projection("projection_synthetic_48x32_fov60", &light, 1);
}

#[test]
fn projection_power_amount_sets_phi() {
    let d65 = Spectrum::d65().luminous_efficacy();
    let light = projector(synthetic_image(48, 32), 60.0, Amount::Lumens(1000.0));
    let lm = light.phi() as f64 * d65;
    eprintln!("projection_power_amount_sets_phi: 1000 lm asked, phi * efficacy = {lm:.4} lm");
    assert!((lm - 1000.0).abs() < 1e-3 * 1000.0, "{lm}");
}

#[test]
fn projection_hard_case_1x1_image() {
    let image = RgbImage { width: 1, height: 1, pixels: vec![Vec3::new(0.2, 0.9, 0.4)] };
    let light = projector(image, 50.0, Amount::Candela(10.0));
    // One texel covering the window: Omega = 4 atan(t^2 / sqrt(1 + 2 t^2)), t = tan 25 deg.
    let t = 25f64.to_radians().tan();
    let omega = 4.0 * (t * t / (1.0 + 2.0 * t * t).sqrt()).atan();
    let y = Vec3::new(0.2, 0.9, 0.4).dot(LUMINANCE_WEIGHTS) as f64;
    let expected = light.intensity.radiometric as f64 * y * omega;
    eprintln!("projection_hard_case_1x1_image: phi {} vs rectangle solid angle form {expected}", light.phi());
    assert!((light.phi() as f64 - expected).abs() < 1e-6 * expected);
    check_projection("projection_hard_case_1x1_image", &light, 11);
}

#[test]
fn projection_hard_case_fov_near_0() {
    let fov_deg = 0.01;
    // Texels here are 4e-6 rad wide; f32 world directions of a rotated light resolve only ~1e-7
    // rad, which would blur texel edges by a few percent, so this light is not rotated.
    let at = Transform::from_translation(Vec3::new(1.0, 2.0, -0.5));
    let light = projector_at(synthetic_image(48, 32), fov_deg, Amount::Candela(250.0), &at);
    // At so small a field the window is flat: phi ~ s * A * mean luminance, A = 4 sx sy.
    let image = synthetic_image(48, 32);
    let mean_y: f64 =
        image.pixels.iter().map(|p| p.dot(LUMINANCE_WEIGHTS) as f64).sum::<f64>() / image.pixels.len() as f64;
    let t = (fov_deg as f64 / 2.0).to_radians().tan();
    let small_angle = light.intensity.radiometric as f64 * 4.0 * t * t * 1.5 * mean_y;
    let rel = (light.phi() as f64 / small_angle - 1.0).abs();
    eprintln!(
        "projection_hard_case_fov_near_0: phi {:.6e} vs small-angle {small_angle:.6e} (rel {rel:.1e})",
        light.phi()
    );
    assert!(rel < 1e-4);
    let phi = light.phi() as f64;
    let importance = estimate(21, |u| {
        light.sample_direction(u).map_or(0.0, |(w, pdf)| light.intensity_toward(w) as f64 / pdf as f64)
    });
    check_mc("projection_hard_case_fov_near_0", "phi vs importance-sampled MC", importance, phi, 1e-3);
    // Uniform sampling of a 3e-8 sr frustum sees nothing: only the pdf agreement is checked.
    check_pdf_agreement(
        "projection_hard_case_fov_near_0",
        22,
        |u| light.sample_direction(u),
        |w| light.pdf_dir(w),
        projection_edge(&light),
    );
}

#[test]
fn projection_hard_case_fov_near_180() {
    let light = projector(synthetic_image(48, 32), 179.0, Amount::Candela(250.0));
    assert!(light.phi().is_finite() && light.phi() > 0.0);
    // The frustum is nearly a hemisphere (its longer side even more so).
    let b = light.bounds();
    eprintln!("projection_hard_case_fov_near_180: cos_theta_o = {}", b.cos_theta_o);
    assert!(b.cos_theta_o > 0.0 && b.cos_theta_o < 0.01);
    check_projection("projection_hard_case_fov_near_180", &light, 31);
}

#[test]
fn projection_hard_case_all_black_image() {
    let image = RgbImage { width: 8, height: 4, pixels: vec![Vec3::ZERO; 32] };
    for amount in [Amount::Candela(100.0), Amount::Lumens(100.0)] {
        let light = projector(image.clone(), 60.0, amount);
        assert_eq!(light.phi(), 0.0, "{amount:?}");
        assert!(light.intensity.radiometric.is_finite());
        assert!(light.sample_direction(Vec2::new(0.3, 0.7)).is_none());
        assert_eq!(light.pdf_dir(light.rotation * Vec3::NEG_Z), 0.0);
        assert!(light.sample_li(&LightSampleContext::at(Vec3::new(1.0, -3.0, -0.5)), ColorQuery::Rgb).is_none());
        assert_eq!(light.bounds().phi, 0.0);
    }
}

#[test]
fn projection_delta_irradiance_is_intensity_cos_over_r2() {
    // A 2 x 2 picture from 3 m above the floor, image top toward -Z, fov 90: the window covers
    // x, z in [-3, 3] on the floor; texel (0, 0) lands at x < 0, z < 0.
    let texels =
        [Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.5, 0.5, 0.5)];
    let image = RgbImage { width: 2, height: 2, pixels: texels.to_vec() };
    let cd = 400.0;
    let transform = Transform::from_translation(Vec3::new(0.0, 3.0, 0.0)).looking_to(Vec3::NEG_Y, Vec3::NEG_Z);
    let light =
        ProjectionLight { amount: Amount::Candela(cd), ..ProjectionLight::new(Arc::new(image), 90f32.to_radians()) }
            .resolve(&transform)
            .unwrap();
    let n = Vec3::Y;
    for (p, texel) in [
        (Vec3::new(-1.0, 0.0, -2.0), texels[0]),
        (Vec3::new(2.5, 0.0, -0.5), texels[1]),
        (Vec3::new(-0.3, 0.0, 1.0), texels[2]),
        (Vec3::new(1.0, 0.0, 2.9), texels[3]),
    ] {
        let s = light.sample_li(&LightSampleContext::on_surface(p, n), ColorQuery::Rgb).expect("inside the frustum");
        let d = Vec3::new(0.0, 3.0, 0.0) - p;
        let (r2, cos) = (d.length_squared(), d.normalize().dot(n));
        let rgb = Vec3::new(s.radiance.0[0], s.radiance.0[1], s.radiance.0[2]);
        let e = rgb.dot(LUMINANCE_WEIGHTS) * s.wi.dot(n) / s.pdf;
        let expected = cd * texel.dot(LUMINANCE_WEIGHTS) * cos / r2;
        let rel = (e / expected - 1.0).abs();
        eprintln!("projection_delta_irradiance: at {p}: E = {e:.6} lx, I cos / r^2 = {expected:.6} lx (rel {rel:.1e})");
        assert!(rel < 1e-4 && s.pdf == 1.0 && (rgb / rgb.max_element() - texel / texel.max_element()).length() < 1e-3);
    }
    // Outside the window (|x| > 3 on the floor) nothing arrives.
    assert!(light.sample_li(&LightSampleContext::on_surface(Vec3::new(3.5, 0.0, 0.0), n), ColorQuery::Rgb).is_none());
}

#[test]
fn projection_white_image_matches_point_light_inside_frustum() {
    let cd = 120.0;
    let image = RgbImage { width: 5, height: 3, pixels: vec![Vec3::ONE; 15] };
    let transform = tilted_transform();
    let proj =
        ProjectionLight { amount: Amount::Candela(cd), ..ProjectionLight::new(Arc::new(image), 40f32.to_radians()) }
            .resolve(&transform)
            .unwrap();
    let point = PointLight::candela(cd).resolve(&transform).unwrap();
    let mut rng = SplitMix64::new(41);
    let (mut inside, mut outside, mut worst) = (0, 0, 0.0f32);
    for _ in 0..20_000 {
        let p = Vec3::new(rng.f32() * 10.0 - 5.0, rng.f32() * 6.0 - 5.0, rng.f32() * 10.0 - 5.0);
        let ctx = LightSampleContext::at(p);
        let lambda = SampledWavelengths::sample_visible(rng.f32());
        let to_light = (transform.translation - p).normalize();
        let local = transform.to_local_direction(-to_light);
        let x = local.x / -local.z;
        let y = local.y / -local.z;
        let (sx, sy) = (proj.half_extent.x, proj.half_extent.y);
        let in_frustum = local.z < 0.0 && x.abs() < sx && y.abs() < sy;
        for query in [ColorQuery::Rgb, ColorQuery::Spectral(&lambda)] {
            match (proj.sample_li(&ctx, query), point.sample_li(&ctx, query)) {
                (Some(a), Some(b)) => {
                    assert!(in_frustum || (x.abs() - sx).abs() < 1e-4 || (y.abs() - sy).abs() < 1e-4);
                    for (va, vb) in a.radiance.0.iter().zip(b.radiance.0.iter()) {
                        worst = worst.max((va - vb).abs() / vb.abs().max(1e-30));
                    }
                    assert_eq!((a.wi, a.pdf, a.p_light), (b.wi, b.pdf, b.p_light));
                    inside += 1;
                }
                (None, Some(_)) => {
                    assert!(!in_frustum || (x.abs() - sx).abs() < 1e-4 || (y.abs() - sy).abs() < 1e-4, "dark at {p}");
                    outside += 1;
                }
                other => panic!("unexpected {other:?}"),
            }
        }
    }
    eprintln!(
        "projection_white_image_matches_point_light: {inside} lit and {outside} dark queries; max rel diff {worst:.1e}"
    );
    assert!(inside > 100 && outside > 100 && worst < 1e-4);
}

#[test]
fn projection_bad_input_is_a_clear_error() {
    let image = Arc::new(synthetic_image(4, 4));
    for fov in [0.0, PI, -1.0, f32::NAN, f32::INFINITY] {
        let err = ProjectionLight::new(image.clone(), fov).resolve(&Transform::IDENTITY).unwrap_err();
        assert!(err.to_string().contains("fov"), "{err}");
    }
    let mut bad = synthetic_image(4, 4);
    bad.pixels[6] = Vec3::new(0.0, f32::NAN, 1.0);
    let err = ProjectionLight::new(Arc::new(bad), 1.0).resolve(&Transform::IDENTITY).unwrap_err();
    assert!(err.to_string().contains("(x 2, y 1)"), "{err}");
    let short = RgbImage { width: 3, height: 3, pixels: vec![Vec3::ONE; 8] };
    assert!(ProjectionLight::new(Arc::new(short), 1.0).resolve(&Transform::IDENTITY).is_err());
    let lux = ProjectionLight { amount: Amount::Lux(5.0), ..ProjectionLight::new(image, 1.0) };
    assert!(matches!(lux.resolve(&Transform::IDENTITY), Err(LightError::WrongUnit { .. })));
}

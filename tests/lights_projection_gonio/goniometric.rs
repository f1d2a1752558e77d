//! Goniometric light: IES and image profiles; phi vs Monte Carlo, pdfs, IES flux, irradiance,
//! hard cases.

use std::f32::consts::PI;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Vec2, Vec3};
use kelvin::geometry::Transform;
use kelvin::light::goniometric::IES_SAMPLING_RESOLUTION;
use kelvin::light::{
    Amount, ColorQuery, GonioProfile, GoniometricLight, LightError, LightSampleContext, PointLight, ResolvedGoniometric,
};
use kelvin::rng::SplitMix64;
use kelvin::sampling::{equal_area_sphere_to_square, sample_uniform_sphere};
use kelvin::scene::ies::IesProfile;
use kelvin::scene::image::{LUMINANCE_WEIGHTS, RgbImage, direction_to_lat_long};
use kelvin::spectrum::{SampledWavelengths, Spectrum};

use crate::common::*;

/// The real IES files under tests/data/ies (the test fails when there are none).
fn real_ies_files(test: &str) -> Vec<PathBuf> {
    let root = crate::files::test_data("ies");
    let dirs = std::fs::read_dir(&root).unwrap_or_else(|e| panic!("{test}: {}: {e}", root.display()));
    let mut files: Vec<PathBuf> = dirs
        .flatten()
        .flat_map(|d| std::fs::read_dir(d.path()).into_iter().flatten().flatten().map(|f| f.path()))
        .filter(|p| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("ies")))
        .collect();
    files.sort();
    assert!(!files.is_empty(), "{test}: no .ies files under {}", root.display());
    files
}

fn file_name(path: &Path) -> String {
    path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default()
}

fn gonio(profile: GonioProfile, amount: Amount, transform: &Transform) -> ResolvedGoniometric {
    GoniometricLight { amount, ..GoniometricLight::new(profile) }.resolve(transform).expect("valid goniometric light")
}

/// Whether world direction `w` from the light lies within 1e-4 texel of a texel edge of the
/// light's sampling grid (the equal-area square, or the lat-long image).
fn gonio_edge(light: &ResolvedGoniometric) -> impl Fn(Vec3) -> bool + '_ {
    move |w| {
        let local = light.rotation.inverse() * w;
        match &light.profile {
            GonioProfile::Ies(_) => {
                let n = IES_SAMPLING_RESOLUTION;
                near_grid_edge(equal_area_sphere_to_square(local), n, n, 1e-4)
            }
            GonioProfile::EqualAreaImage(image) => {
                near_grid_edge(equal_area_sphere_to_square(local), image.width, image.height, 1e-4)
            }
            GonioProfile::LatLong(image) => {
                near_grid_edge(direction_to_lat_long(local), image.width, image.height, 1e-4)
            }
        }
    }
}

/// (a), (b), (c) for one goniometric light; returns (importance, uniform) relative errors of phi.
fn check_gonio(test: &str, light: &ResolvedGoniometric, seed: u64) -> (f64, f64) {
    let phi = light.phi() as f64;
    let importance = estimate(seed, |u| {
        light.sample_emission_direction(u).map_or(0.0, |(w, pdf)| light.intensity_toward(w) as f64 / pdf as f64)
    });
    let rel_is = check_mc(test, "phi vs importance-sampled MC", importance, phi, 1e-3);
    let uniform = estimate(seed + 1, |u| light.intensity_toward(sample_uniform_sphere(u)) as f64 * 4.0 * PI as f64);
    let rel_uni = check_mc(test, "phi vs uniform-sphere MC", uniform, phi, UNIFORM_TOL);
    check_pdf_agreement(
        test,
        seed + 2,
        |u| light.sample_emission_direction(u),
        |w| light.pdf_emission_direction(w),
        gonio_edge(light),
    );
    let integral =
        estimate(seed + 3, |u| light.pdf_emission_direction(sample_uniform_sphere(u)) as f64 * 4.0 * PI as f64);
    check_mc(test, "integral of the pdf over the sphere", integral, 1.0, UNIFORM_TOL);
    (rel_is, rel_uni)
}

#[test]
fn gonio_ies_phi_matches_monte_carlo_and_pdfs_agree() {
    let test = "gonio_ies_phi_matches_monte_carlo";
    let files = real_ies_files(test);
    for (k, path) in files.iter().enumerate() {
        let ies = Arc::new(IesProfile::from_file(path).expect("real IES file parses"));
        let light = gonio(GonioProfile::Ies(ies), Amount::Candela(1.0), &tilted_transform());
        check_gonio(&format!("{test} [{}]", file_name(path)), &light, 100 + 10 * k as u64);
    }
}

#[test]
fn gonio_ies_default_amount_emits_the_files_flux() {
    let test = "gonio_ies_default_amount_emits_the_files_flux";
    let files = real_ies_files(test);
    let efficacy = Spectrum::d65().luminous_efficacy();
    for path in files {
        let ies = Arc::new(IesProfile::from_file(&path).expect("real IES file parses"));
        let light =
            gonio(GonioProfile::Ies(ies.clone()), GoniometricLight::from_ies(ies.clone()).amount, &Transform::IDENTITY);
        let emitted_lm = light.phi() as f64 * efficacy;
        let flux = ies.integrated_flux_lm();
        let rel = (emitted_lm / flux - 1.0).abs();
        eprintln!(
            "{test} [{}]: emitted {emitted_lm:.2} lm, file's integrated flux {flux:.2} lm (rel {rel:.1e}), stated lamp lumens {}",
            file_name(&path),
            ies.stated_lumens().map_or("none (absolute photometry)".into(), |l| format!(
                "{l:.1} (luminaire efficiency {:.1}%)",
                100.0 * flux / l
            ))
        );
        assert!(rel < 0.01);
        // Relative photometry states the bare lamps' lumens: a luminaire cannot emit more.
        if let Some(stated) = ies.stated_lumens() {
            assert!(emitted_lm <= 1.01 * stated);
        }
    }
}

/// An IES LM-63-2002 type C file with one horizontal angle (rotational symmetry).
fn synthetic_ies(lamp_lumens: f64, vertical_deg: &[f64], candela: &[f64]) -> String {
    let fmt = |v: &[f64]| v.iter().map(|x| format!("{x}")).collect::<Vec<_>>().join(" ");
    format!(
        "IESNA:LM-63-2002\n[TEST] kelvin synthetic\nTILT=NONE\n1 {lamp_lumens} 1 {} 1 1 2 0 0 0\n1 1 100\n{}\n0\n{}\n",
        vertical_deg.len(),
        fmt(vertical_deg),
        fmt(candela)
    )
}

#[test]
fn gonio_ies_stated_lumens_where_they_describe_the_luminaire() {
    let test = "gonio_ies_stated_lumens";
    let efficacy = Spectrum::d65().luminous_efficacy();
    // A bare isotropic 1000 lm lamp, and a cosine downlight of 1000 lm (I0 = 1000 / pi), whose
    // stated lumens are the luminaire's.
    let down_angles: Vec<f64> = (0..=18).map(|k| 5.0 * k as f64).collect();
    let down_cd: Vec<f64> =
        down_angles.iter().map(|g: &f64| 1000.0 / std::f64::consts::PI * g.to_radians().cos()).collect();
    let files = [
        ("isotropic", synthetic_ies(1000.0, &[0.0, 90.0, 180.0], &[1000.0 / (4.0 * std::f64::consts::PI); 3])),
        ("cosine downlight", synthetic_ies(1000.0, &down_angles, &down_cd)),
    ];
    for (k, (name, text)) in files.iter().enumerate() {
        let ies = Arc::new(IesProfile::parse(text, name).expect("synthetic IES parses"));
        let light = gonio(GonioProfile::Ies(ies.clone()), Amount::Candela(1.0), &tilted_transform());
        let emitted_lm = light.phi() as f64 * efficacy;
        let stated = ies.stated_lumens().unwrap();
        let rel = (emitted_lm / stated - 1.0).abs();
        eprintln!(
            "{test} [{name}]: emitted {emitted_lm:.3} lm, integrated {:.3} lm, stated {stated:.1} lm (rel {rel:.1e})",
            ies.integrated_flux_lm()
        );
        assert!(rel < 0.01);
        check_gonio(&format!("{test} [{name}]"), &light, 200 + 10 * k as u64);
    }
}

#[test]
fn gonio_ies_hard_case_single_vertical_angle() {
    // One vertical angle: a profile without extent. The parser refuses it with a line number; if
    // it is ever accepted, the light must stay finite and dark or consistent.
    let text = "IESNA:LM-63-2002\nTILT=NONE\n1 1000 1 1 1 1 2 0 0 0\n1 1 100\n0\n0\n500\n";
    match IesProfile::parse(text, "single vertical angle") {
        Err(e) => {
            eprintln!("gonio_ies_hard_case_single_vertical_angle: refused: {e}");
            assert!(e.to_string().contains("vertical"), "{e}");
        }
        Ok(ies) => {
            let light = gonio(GonioProfile::Ies(Arc::new(ies.clone())), Amount::Lumens(100.0), &Transform::IDENTITY);
            assert!(light.phi().is_finite() && light.intensity.radiometric.is_finite());
            eprintln!("gonio_ies_hard_case_single_vertical_angle: accepted, flux {} lm", ies.integrated_flux_lm());
            if light.phi() == 0.0 {
                assert!(light.sample_emission_direction(Vec2::splat(0.5)).is_none());
            }
        }
    }
}

#[test]
fn gonio_ies_delta_irradiance_is_intensity_cos_over_r2() {
    let test = "gonio_ies_delta_irradiance";
    let files = real_ies_files(test);
    let ies = Arc::new(IesProfile::from_file(&files[0]).unwrap());
    // Aimed down from 3 m: local -Z is world -Y, local +X world -X, local +Y world +Z.
    let at = Vec3::new(0.0, 3.0, 0.0);
    let transform = Transform::from_translation(at).looking_to(Vec3::NEG_Y, Vec3::Z);
    let scale = 2.0;
    let light = gonio(GonioProfile::Ies(ies.clone()), Amount::Candela(scale), &transform);
    let efficacy = Spectrum::d65().luminous_efficacy() as f32;
    let lambda = SampledWavelengths::sample_visible(0.37);
    let point = PointLight::candela(1.0).resolve(&transform).unwrap();
    let mut lit = 0;
    for (a, b) in [(0.0, 0.0), (1.0, 0.5), (-2.0, 1.5), (0.5, -3.0), (4.0, 4.0), (-6.0, -1.0)] {
        let p = Vec3::new(a, 0.0, b);
        let ctx = LightSampleContext::on_surface(p, Vec3::Y);
        let d = at - p;
        let (r2, cos) = (d.length_squared(), d.normalize().y);
        // The file's own angles: gamma from nadir, C from local +X toward local +Y.
        let gamma = (3.0 / d.length()).acos().to_degrees() as f64;
        let c = (b as f64).atan2(-a as f64).to_degrees();
        let cd = scale as f64 * ies.candela(gamma, c);
        let expected = (cd as f32) * cos / r2;
        match light.sample_li(&ctx, ColorQuery::Rgb) {
            Some(s) => {
                let e = Vec3::new(s.radiance.0[0], s.radiance.0[1], s.radiance.0[2]).dot(LUMINANCE_WEIGHTS)
                    * s.wi.dot(Vec3::Y);
                let rel = (e / expected - 1.0).abs();
                eprintln!(
                    "{test}: at {p}: E = {e:.6} lx, I cos / r^2 = {expected:.6} lx (gamma {gamma:.2}, C {c:.2}; rel {rel:.1e})"
                );
                assert!(rel < 1e-4 && s.pdf == 1.0);
                // Spectral mode: the point light's spectral radiance times the relative intensity.
                let spectral = light.sample_li(&ctx, ColorQuery::Spectral(&lambda)).unwrap();
                let reference = point.sample_li(&ctx, ColorQuery::Spectral(&lambda)).unwrap();
                for (x, y) in spectral.radiance.0.iter().zip(reference.radiance.0) {
                    assert!((x - y * cd as f32).abs() <= 1e-4 * x.abs());
                }
                let radiometric = light.intensity_toward(-s.wi) * efficacy;
                assert!((radiometric / cd as f32 - 1.0).abs() < 1e-4);
                lit += 1;
            }
            None => assert!(cd == 0.0, "dark at {p} but the file gives {cd} cd"),
        }
    }
    assert!(lit >= 3);
}

/// A 32 x 32 equal-area picture (bright band, gradient, some black texels) and a 64 x 32 lat-long one.
fn gonio_images() -> (RgbImage, RgbImage) {
    let texel = |x: usize, y: usize| {
        if (x * 5 + y * 3).is_multiple_of(13) {
            return Vec3::ZERO;
        }
        Vec3::new(
            0.2 + x as f32 / 40.0,
            1.0 + (0.3 * y as f32).sin(),
            if (x + y).is_multiple_of(4) { 3.0 } else { 0.1 },
        )
    };
    let grid = |w: usize, h: usize| (0..h).flat_map(|y| (0..w).map(move |x| texel(x, y))).collect();
    (RgbImage { width: 32, height: 32, pixels: grid(32, 32) }, RgbImage { width: 64, height: 32, pixels: grid(64, 32) })
}

#[test]
fn gonio_images_phi_matches_monte_carlo_and_pdfs_agree() {
    let (equal_area, lat_long) = gonio_images();
    let ea = gonio(GonioProfile::EqualAreaImage(Arc::new(equal_area)), Amount::Candela(50.0), &tilted_transform());
    check_gonio("gonio_equal_area_32x32", &ea, 300);
    let ll = gonio(GonioProfile::LatLong(Arc::new(lat_long)), Amount::Candela(50.0), &tilted_transform());
    check_gonio("gonio_lat_long_64x32", &ll, 310);
    // A power amount normalises either.
    let efficacy = Spectrum::d65().luminous_efficacy();
    let (equal_area, _) = gonio_images();
    let lm = gonio(GonioProfile::EqualAreaImage(Arc::new(equal_area)), Amount::Lumens(500.0), &Transform::IDENTITY);
    assert!((lm.phi() as f64 * efficacy / 500.0 - 1.0).abs() < 1e-5);
}

#[test]
fn gonio_hard_case_1x1_equal_area_image_is_a_point_light() {
    let image = RgbImage { width: 1, height: 1, pixels: vec![Vec3::ONE] };
    let light = gonio(GonioProfile::EqualAreaImage(Arc::new(image)), Amount::Candela(30.0), &tilted_transform());
    let point = PointLight::candela(30.0).resolve(&tilted_transform()).unwrap();
    assert!((light.phi() / point.phi() - 1.0).abs() < 1e-6, "{} vs {}", light.phi(), point.phi());
    check_gonio("gonio_hard_case_1x1_equal_area", &light, 400);
    let mut rng = SplitMix64::new(401);
    for _ in 0..1000 {
        let p = Vec3::new(rng.f32() * 8.0 - 4.0, rng.f32() * 8.0 - 4.0, rng.f32() * 8.0 - 4.0);
        let lambda = SampledWavelengths::sample_visible(rng.f32());
        for query in [ColorQuery::Rgb, ColorQuery::Spectral(&lambda)] {
            let (a, b) = (
                light.sample_li(&LightSampleContext::at(p), query),
                point.sample_li(&LightSampleContext::at(p), query),
            );
            let (a, b) = (a.unwrap(), b.unwrap());
            for (x, y) in a.radiance.0.iter().zip(b.radiance.0) {
                assert!((x - y).abs() <= 1e-4 * y.abs(), "{x} vs {y}");
            }
        }
    }
}

#[test]
fn gonio_hard_case_all_black_images() {
    for profile in [
        GonioProfile::EqualAreaImage(Arc::new(RgbImage { width: 4, height: 4, pixels: vec![Vec3::ZERO; 16] })),
        GonioProfile::LatLong(Arc::new(RgbImage { width: 8, height: 4, pixels: vec![Vec3::ZERO; 32] })),
    ] {
        for amount in [Amount::Candela(10.0), Amount::Lumens(10.0)] {
            let light = gonio(profile.clone(), amount, &tilted_transform());
            assert_eq!(light.phi(), 0.0);
            assert!(light.intensity.radiometric.is_finite());
            assert!(light.sample_emission_direction(Vec2::new(0.2, 0.9)).is_none());
            assert_eq!(light.pdf_emission_direction(Vec3::Y), 0.0);
            assert!(light.sample_li(&LightSampleContext::at(Vec3::new(0.0, -2.0, 0.0)), ColorQuery::Rgb).is_none());
        }
    }
}

#[test]
fn gonio_bad_input_is_a_clear_error() {
    let oblong = RgbImage { width: 8, height: 4, pixels: vec![Vec3::ONE; 32] };
    let err = GoniometricLight::new(GonioProfile::EqualAreaImage(Arc::new(oblong)))
        .resolve(&Transform::IDENTITY)
        .unwrap_err();
    assert!(err.to_string().contains("square"), "{err}");
    let mut bad = RgbImage { width: 4, height: 2, pixels: vec![Vec3::ONE; 8] };
    bad.pixels[5] = Vec3::new(-1.0, 0.0, 0.0);
    let err = GoniometricLight::new(GonioProfile::LatLong(Arc::new(bad))).resolve(&Transform::IDENTITY).unwrap_err();
    assert!(err.to_string().contains("(x 1, y 1)"), "{err}");
    let image = Arc::new(RgbImage { width: 2, height: 2, pixels: vec![Vec3::ONE; 4] });
    let light =
        GoniometricLight { amount: Amount::Nits(1.0), ..GoniometricLight::new(GonioProfile::EqualAreaImage(image)) };
    assert!(matches!(light.resolve(&Transform::IDENTITY), Err(LightError::WrongUnit { .. })));
}

//! Infinite lights: uniform sky and image (lat-long) environment maps on synthetic maps. Physics
//! (irradiance pi L, power vs Monte Carlo), pdf consistency (sample pdf == pdf_li, pdfs integrate
//! to 1), MIS compensation, and the hard cases (black map, one 1e9 texel, 1x1 and 1xN maps,
//! non-finite texels). The real maps are in lights_infinite_maps.rs.

mod common;
#[path = "support/infinite.rs"]
mod support;

use std::f64::consts::PI;
use std::sync::Arc;

use glam::{Quat, Vec2, Vec3};
use kelvin::geometry::Transform;
use kelvin::light::{
    Amount, ColorQuery, EnvLookup, ImageInfiniteLight, LightError, LightFlags, LightSampleContext,
    ResolvedImageInfinite, SceneSphere, UniformInfiniteLight,
};
use kelvin::rng::SplitMix64;
use kelvin::sampling::{sample_uniform_sphere, uniform_sphere_pdf};
use kelvin::scene::image::{LUMINANCE_WEIGHTS, RgbImage, direction_to_lat_long};
use kelvin::spectrum::{SampledSpectrum, SampledWavelengths};
use support::{Stats, image, rel_diff, resolve, surface_ctx, test_sky, tilted, y_of};

// ---------------------------------------------------------------------------------------------
// Uniform sky
// ---------------------------------------------------------------------------------------------

#[test]
fn uniform_sky_irradiance_is_pi_l() {
    let l_nits = 1234.5;
    let sky = UniformInfiniteLight::nits(l_nits).resolve(SceneSphere::default()).unwrap();
    let mut rng = SplitMix64::new(1);
    let n = surface_ctx().n;
    // On a surface: cosine sampling, zero variance. Off a surface: uniform sphere, estimate of
    // the integral of L max(0, cos) about the same normal.
    for (name, ctx) in
        [("surface (cosine)", surface_ctx()), ("no normal (uniform)", LightSampleContext::at(Vec3::ZERO))]
    {
        let mut e = Stats::default();
        for _ in 0..100_000 {
            let s = sky.sample_li(&ctx, rng.vec2(), ColorQuery::Rgb).expect("sky sample");
            e.add(y_of(s.radiance) * n.dot(s.wi).max(0.0) as f64 / s.pdf as f64);
        }
        e.check(&format!("uniform sky irradiance, {name}"), PI * l_nits as f64, 1e-4 * PI * l_nits as f64);
    }
}

#[test]
fn uniform_sky_pdf_of_samples_matches_pdf_li_and_integrates_to_one() {
    let sky = UniformInfiniteLight::default().resolve(SceneSphere::default()).unwrap();
    assert_eq!(sky.flags(), LightFlags::INFINITE);
    let mut rng = SplitMix64::new(2);
    for ctx in [surface_ctx(), LightSampleContext::at(Vec3::ONE)] {
        let mut worst = 0.0f32;
        for _ in 0..20_000 {
            let s = sky.sample_li(&ctx, rng.vec2(), ColorQuery::Rgb).unwrap();
            worst = worst.max(rel_diff(s.pdf, sky.pdf_li(&ctx, s.wi)));
            assert!((s.wi.length() - 1.0).abs() < 1e-5);
        }
        eprintln!("uniform sky: worst relative pdf mismatch {worst:.2e}");
        assert!(worst <= 1e-4);
        let mut integral = Stats::default();
        for _ in 0..200_000 {
            let w = sample_uniform_sphere(rng.vec2());
            integral.add(sky.pdf_li(&ctx, w) as f64 / uniform_sphere_pdf() as f64);
        }
        integral.check("uniform sky: integral of pdf_li", 1.0, 1e-6);
    }
}

#[test]
fn uniform_sky_power_is_4_pi2_r2_l() {
    let scene = SceneSphere { center: Vec3::ZERO, radius: 3.0 };
    let sky = UniformInfiniteLight { amount: Amount::WattsPerM2Sr(2.0), ..Default::default() }.resolve(scene).unwrap();
    let expected = 4.0 * PI * PI * 9.0 * 2.0;
    let rel = (sky.phi() as f64 - expected).abs() / expected;
    eprintln!("uniform sky phi: {} vs {expected}, rel err {rel:.2e}", sky.phi());
    assert!(rel < 1e-5);
    let far = sky.sample_li(&LightSampleContext::at(Vec3::new(10.0, 0.0, 0.0)), Vec2::splat(0.3), ColorQuery::Rgb);
    assert!(far.unwrap().p_light.length() > scene.radius, "sample point lies outside the scene");
}

#[test]
fn uniform_sky_rejects_wrong_units_and_bad_values() {
    let lux = UniformInfiniteLight { amount: Amount::Lux(5.0), ..Default::default() };
    assert!(matches!(lux.resolve(SceneSphere::default()), Err(LightError::WrongUnit { .. })));
    for v in [f32::NAN, -1.0, f32::INFINITY] {
        let bad = UniformInfiniteLight::nits(v);
        assert!(matches!(bad.resolve(SceneSphere::default()), Err(LightError::BadAmount { .. })), "{v}");
    }
}

// ---------------------------------------------------------------------------------------------
// Image light on synthetic maps
// ---------------------------------------------------------------------------------------------

#[test]
fn image_light_pdf_of_samples_matches_pdf_li() {
    let mut rng = SplitMix64::new(3);
    for lookup in [EnvLookup::Nearest, EnvLookup::Bilinear] {
        let light = resolve(&ImageInfiniteLight { lookup, ..ImageInfiniteLight::new(test_sky(64, 32)) }, tilted());
        assert_eq!(light.flags(), LightFlags::INFINITE);
        for mis in [false, true] {
            let mut worst = 0.0f32;
            for _ in 0..50_000 {
                let ctx = surface_ctx();
                let s = if mis {
                    light.sample_li_mis(&ctx, rng.vec2(), ColorQuery::Rgb)
                } else {
                    light.sample_li(&ctx, rng.vec2(), ColorQuery::Rgb)
                };
                let s = s.expect("lit map always samples");
                let pdf = if mis { light.pdf_li_mis(s.wi) } else { light.pdf_li(s.wi) };
                worst = worst.max(rel_diff(s.pdf, pdf));
                assert_eq!(s.radiance, light.le(s.wi, ColorQuery::Rgb));
                // The escaping-ray pair from one lookup is the two lookups, bit for bit.
                let w = sample_uniform_sphere(rng.vec2());
                let le = light.le(w, ColorQuery::Rgb);
                let pdf_w = if mis { light.pdf_li_mis(w) } else { light.pdf_li(w) };
                let pair = light.le_and_pdf(w, ColorQuery::Rgb, mis);
                assert_eq!(
                    pair.map(|(l, p)| (l.0, p.to_bits())),
                    (le.0 != [0.0; 4]).then_some((le.0, pdf_w.to_bits()))
                );
                assert!(s.pdf.is_finite() && s.pdf > 0.0 && s.radiance.is_finite());
            }
            eprintln!("image light {lookup:?} mis={mis}: worst relative pdf mismatch {worst:.2e}");
            assert!(worst <= 1e-4);
        }
    }
}

#[test]
fn image_light_pdf_integrates_to_one() {
    let mut rng = SplitMix64::new(4);
    for lookup in [EnvLookup::Nearest, EnvLookup::Bilinear] {
        let light = resolve(&ImageInfiniteLight { lookup, ..ImageInfiniteLight::new(test_sky(64, 32)) }, tilted());
        for mis in [false, true] {
            let mut integral = Stats::default();
            for _ in 0..200_000 {
                let w = sample_uniform_sphere(rng.vec2());
                let pdf = if mis { light.pdf_li_mis(w) } else { light.pdf_li(w) };
                integral.add(pdf as f64 / uniform_sphere_pdf() as f64);
            }
            integral.check(&format!("image light {lookup:?} mis={mis}: integral of pdf_li"), 1.0, 1e-6);
        }
    }
}

#[test]
fn image_light_phi_matches_monte_carlo_integral_of_le() {
    let mut rng = SplitMix64::new(5);
    for lookup in [EnvLookup::Nearest, EnvLookup::Bilinear] {
        let comp = ImageInfiniteLight { lookup, scale: 3.0, ..ImageInfiniteLight::new(test_sky(48, 24)) };
        let light = resolve(&comp, tilted());
        let disc = PI * 25.0;
        // Importance-sampled (low variance) and uniform-sphere (independent of the tables).
        let (mut by_light, mut by_sphere) = (Stats::default(), Stats::default());
        for _ in 0..200_000 {
            let s = light.sample_li(&LightSampleContext::at(Vec3::ZERO), rng.vec2(), ColorQuery::Rgb).unwrap();
            by_light.add(disc * y_of(s.radiance) / s.pdf as f64);
            let w = sample_uniform_sphere(rng.vec2());
            by_sphere.add(disc * y_of(light.le(w, ColorQuery::Rgb)) / uniform_sphere_pdf() as f64);
        }
        let phi_lm = light.luminous_phi() as f64;
        by_light.check(&format!("{lookup:?} luminous phi vs light-sampled MC"), phi_lm, 1e-3 * phi_lm);
        by_sphere.check(&format!("{lookup:?} luminous phi vs sphere-sampled MC"), phi_lm, 1e-3 * phi_lm);
        // Radiometric power: the luminous one over the spectrum's efficacy (D65 here).
        let k = light.emitter.luminous() as f64 / light.emitter.radiometric as f64;
        let rel = (light.phi() as f64 * k - phi_lm).abs() / phi_lm;
        eprintln!("{lookup:?}: phi * efficacy vs luminous phi rel err {rel:.2e}");
        assert!(rel < 1e-3);
    }
}

#[test]
fn nearest_lookup_importance_is_perfect_for_grey_maps() {
    // Sampling density proportional to the texel's luminance: Y(le) / pdf is the same for every
    // sample (pbrt-v4 lights_test: "importance should be perfect").
    let grey = image(32, 16, |x, y| Vec3::splat(0.1 + ((x * 13 + y * 7) % 11) as f32));
    let light = resolve(&ImageInfiniteLight { lookup: EnvLookup::Nearest, ..ImageInfiniteLight::new(grey) }, tilted());
    let mut rng = SplitMix64::new(6);
    let mut est = Stats::default();
    for _ in 0..20_000 {
        let s = light.sample_li(&surface_ctx(), rng.vec2(), ColorQuery::Rgb).unwrap();
        est.add(PI * 25.0 * y_of(s.radiance) / s.pdf as f64);
    }
    let rel_sd = est.sigma() * est.n.sqrt() / est.mean();
    let rel = (est.mean() - light.luminous_phi() as f64).abs() / light.luminous_phi() as f64;
    eprintln!("perfect importance: per-sample relative spread {rel_sd:.2e}, phi rel err {rel:.2e}");
    assert!(rel_sd < 1e-3 && rel < 1e-3);
}

#[test]
fn constant_image_irradiance_is_pi_l() {
    let mut rng = SplitMix64::new(7);
    let (c, scale) = (Vec3::new(0.8, 0.8, 0.8), 250.0);
    let l_nits = scale as f64 * c.dot(LUMINANCE_WEIGHTS) as f64;
    for (w, h) in [(16, 8), (1, 1), (7, 3)] {
        for lookup in [EnvLookup::Nearest, EnvLookup::Bilinear] {
            let comp = ImageInfiniteLight { lookup, scale, ..ImageInfiniteLight::new(image(w, h, |_, _| c)) };
            let light = resolve(&comp, tilted());
            let ctx = surface_ctx();
            let mut e = Stats::default();
            for _ in 0..100_000 {
                let s = light.sample_li(&ctx, rng.vec2(), ColorQuery::Rgb).unwrap();
                e.add(y_of(s.radiance) * ctx.n.dot(s.wi).max(0.0) as f64 / s.pdf as f64);
            }
            e.check(&format!("constant {w}x{h} {lookup:?} map irradiance"), PI * l_nits, 1e-4 * PI * l_nits);
            let phi_rel =
                (light.luminous_phi() as f64 - 4.0 * PI * PI * 25.0 * l_nits).abs() / light.luminous_phi() as f64;
            assert!(phi_rel < 1e-4, "{w}x{h}: luminous phi rel err {phi_rel}");
        }
    }
}

#[test]
fn compensated_mis_matches_complete_light_sampling() {
    // Irradiance from a sky with a small bright sun: MIS (balance heuristic) of compensated light
    // samples with cosine samples vs light-only complete sampling. Both must be unbiased.
    let sky = image(64, 32, |x, y| if (x, y) == (40, 10) { Vec3::splat(5000.0) } else { Vec3::new(0.4, 0.6, 1.0) });
    let light = resolve(&ImageInfiniteLight::new(sky), Quat::IDENTITY);
    assert!(light.tables.compensated.is_some());
    let ctx = surface_ctx();
    let frame = kelvin::sampling::Frame::from_z(ctx.n);
    let mut rng = SplitMix64::new(8);
    let (mut mis, mut complete) = (Stats::default(), Stats::default());
    for _ in 0..200_000 {
        let mut f = 0.0;
        if let Some(s) = light.sample_li_mis(&ctx, rng.vec2(), ColorQuery::Rgb) {
            let cos = ctx.n.dot(s.wi).max(0.0) as f64;
            let p_bsdf = cos / PI;
            f += y_of(s.radiance) * cos / (s.pdf as f64 + p_bsdf);
        }
        let wi = frame.from_local(kelvin::sampling::sample_cosine_hemisphere(rng.vec2())).normalize();
        let cos = ctx.n.dot(wi).max(0.0) as f64;
        if cos > 0.0 {
            let p_bsdf = cos / PI;
            f += y_of(light.le(wi, ColorQuery::Rgb)) * cos / (p_bsdf + light.pdf_li_mis(wi) as f64);
        }
        mis.add(f);
        let s = light.sample_li(&ctx, rng.vec2(), ColorQuery::Rgb).unwrap();
        complete.add(y_of(s.radiance) * ctx.n.dot(s.wi).max(0.0) as f64 / s.pdf as f64);
    }
    let (a, b) = (mis.mean(), complete.mean());
    let sigma = (mis.sigma().powi(2) + complete.sigma().powi(2)).sqrt();
    eprintln!(
        "MIS-compensated {a:.5e} (+-{:.1e}) vs complete {b:.5e} (+-{:.1e}), rel diff {:.2e}",
        mis.sigma(),
        complete.sigma(),
        (a - b).abs() / b
    );
    assert!((a - b).abs() <= 3.0 * sigma, "{a} vs {b}, 3 sigma {}", 3.0 * sigma);
}

#[test]
fn rotation_turns_the_map() {
    let sky = test_sky(32, 16);
    let rot = tilted();
    let (turned, plain) =
        (resolve(&ImageInfiniteLight::new(sky.clone()), rot), resolve(&ImageInfiniteLight::new(sky), Quat::IDENTITY));
    let mut rng = SplitMix64::new(9);
    for _ in 0..1000 {
        let d = sample_uniform_sphere(rng.vec2());
        assert!(
            rel_diff(y_of(turned.le(rot * d, ColorQuery::Rgb)) as f32, y_of(plain.le(d, ColorQuery::Rgb)) as f32)
                < 1e-3
        );
        assert!(
            rel_diff(turned.pdf_li(rot * d), plain.pdf_li(d)) < 1e-3
                || (turned.pdf_li(rot * d) - plain.pdf_li(d)).abs() < 1e-6
        );
    }
}

#[test]
fn spectral_mode_samples_are_finite_and_match_le() {
    let light = resolve(&ImageInfiniteLight::new(test_sky(32, 16)), tilted());
    let lambda = SampledWavelengths::sample_visible(0.37);
    let mut rng = SplitMix64::new(10);
    for _ in 0..1000 {
        let s = light.sample_li(&surface_ctx(), rng.vec2(), ColorQuery::Spectral(&lambda)).unwrap();
        assert!(s.radiance.is_finite() && s.radiance.0.iter().all(|&v| v >= 0.0));
        assert_eq!(s.radiance, light.le(s.wi, ColorQuery::Spectral(&lambda)));
    }
}

// ---------------------------------------------------------------------------------------------
// Hard cases
// ---------------------------------------------------------------------------------------------

/// Every public output of `light` is finite over a batch of samples and directions.
fn assert_outputs_finite(light: &ResolvedImageInfinite, name: &str) {
    let mut rng = SplitMix64::new(11);
    assert!(light.phi().is_finite() && light.luminous_phi().is_finite(), "{name}: phi");
    for _ in 0..2000 {
        let w = sample_uniform_sphere(rng.vec2());
        assert!(light.pdf_li(w).is_finite() && light.pdf_li_mis(w).is_finite(), "{name}: pdf at {w}");
        assert!(light.le(w, ColorQuery::Rgb).is_finite(), "{name}: le at {w}");
        for s in [
            light.sample_li(&surface_ctx(), rng.vec2(), ColorQuery::Rgb),
            light.sample_li_mis(&surface_ctx(), rng.vec2(), ColorQuery::Rgb),
        ]
        .into_iter()
        .flatten()
        {
            assert!(s.pdf.is_finite() && s.pdf > 0.0 && s.radiance.is_finite() && s.wi.is_finite(), "{name}: {s:?}");
        }
    }
    // The poles and the seam.
    for w in [Vec3::Y, -Vec3::Y, -Vec3::X, Vec3::new(-1.0, 0.0, -1e-7).normalize()] {
        assert!(light.pdf_li(w).is_finite() && light.le(w, ColorQuery::Rgb).is_finite(), "{name}: at {w}");
    }
}

#[test]
fn all_zero_map_never_samples_has_zero_pdf_and_zero_power() {
    for lookup in [EnvLookup::Nearest, EnvLookup::Bilinear] {
        let light = resolve(
            &ImageInfiniteLight { lookup, ..ImageInfiniteLight::new(image(16, 8, |_, _| Vec3::ZERO)) },
            tilted(),
        );
        assert!(light.tables.distribution.is_none() && light.tables.compensated.is_none());
        let mut rng = SplitMix64::new(12);
        for _ in 0..100 {
            assert!(light.sample_li(&surface_ctx(), rng.vec2(), ColorQuery::Rgb).is_none());
            assert!(light.sample_li_mis(&surface_ctx(), rng.vec2(), ColorQuery::Rgb).is_none());
            let w = sample_uniform_sphere(rng.vec2());
            assert_eq!((light.pdf_li(w), light.pdf_li_mis(w)), (0.0, 0.0));
            assert_eq!(light.le(w, ColorQuery::Rgb), SampledSpectrum::default());
        }
        assert_eq!((light.phi(), light.luminous_phi()), (0.0, 0.0));
        assert_outputs_finite(&light, "all-zero map");
    }
}

#[test]
fn single_1e9_texel_draws_most_samples_into_its_cell() {
    let (w, h, hot) = (64usize, 32usize, (21usize, 9usize));
    let img = image(w, h, |x, y| if (x, y) == hot { Vec3::splat(1e9) } else { Vec3::ONE });
    for lookup in [EnvLookup::Nearest, EnvLookup::Bilinear] {
        let light = resolve(&ImageInfiniteLight { lookup, ..ImageInfiniteLight::new(img.clone()) }, Quat::IDENTITY);
        assert_outputs_finite(&light, "1e9 texel");
        let mut rng = SplitMix64::new(13);
        let (n, mut in_cell, mut in_block) = (100_000, 0, 0);
        let mut phi = Stats::default();
        for _ in 0..n {
            let s = light.sample_li(&LightSampleContext::at(Vec3::ZERO), rng.vec2(), ColorQuery::Rgb).unwrap();
            let uv = direction_to_lat_long(s.wi);
            let (x, y) = ((uv.x * w as f32) as usize, (uv.y * h as f32) as usize);
            in_cell += usize::from((x, y) == hot);
            in_block += usize::from(x.abs_diff(hot.0) <= 1 && y.abs_diff(hot.1) <= 1);
            phi.add(PI * 25.0 * y_of(s.radiance) / s.pdf as f64);
        }
        let (f_cell, f_block) = (in_cell as f64 / n as f64, in_block as f64 / n as f64);
        eprintln!("1e9 texel {lookup:?}: {f_cell:.4} of samples in its cell, {f_block:.6} in its 3x3 block");
        // Nearest: all the texel's mass; bilinear: its footprint filter keeps 36/64 in the cell.
        let min_cell = if lookup == EnvLookup::Nearest { 0.999 } else { 0.55 };
        assert!(f_cell > min_cell && f_block > 0.999);
        phi.check(
            &format!("1e9 texel {lookup:?}: luminous phi"),
            light.luminous_phi() as f64,
            1e-3 * light.luminous_phi() as f64,
        );
    }
}

#[test]
fn one_by_one_and_one_by_n_maps_sample_consistently() {
    let maps = [
        ("1x1", image(1, 1, |_, _| Vec3::new(0.2, 0.5, 0.9))),
        ("1x16", image(1, 16, |_, y| Vec3::splat(1.0 + y as f32))),
        ("16x1", image(16, 1, |x, _| Vec3::splat(1.0 + (x % 5) as f32))),
    ];
    let mut rng = SplitMix64::new(14);
    for (name, img) in maps {
        for lookup in [EnvLookup::Nearest, EnvLookup::Bilinear] {
            let light = resolve(&ImageInfiniteLight { lookup, ..ImageInfiniteLight::new(img.clone()) }, tilted());
            assert_outputs_finite(&light, name);
            let (mut phi, mut integral) = (Stats::default(), Stats::default());
            let mut worst = 0.0f32;
            for _ in 0..100_000 {
                let s = light.sample_li(&LightSampleContext::at(Vec3::ZERO), rng.vec2(), ColorQuery::Rgb).unwrap();
                worst = worst.max(rel_diff(s.pdf, light.pdf_li(s.wi)));
                phi.add(PI * 25.0 * y_of(s.radiance) / s.pdf as f64);
                integral.add(light.pdf_li(sample_uniform_sphere(rng.vec2())) as f64 / uniform_sphere_pdf() as f64);
            }
            eprintln!("{name} {lookup:?}: worst pdf mismatch {worst:.1e}");
            assert!(worst <= 1e-4);
            phi.check(
                &format!("{name} {lookup:?}: luminous phi"),
                light.luminous_phi() as f64,
                1e-3 * light.luminous_phi() as f64,
            );
            integral.check(&format!("{name} {lookup:?}: integral of pdf_li"), 1.0, 1e-3);
        }
    }
}

#[test]
fn non_finite_texels_passed_directly_are_black() {
    let img = image(8, 4, |x, y| match (x, y) {
        (1, 1) => Vec3::new(f32::NAN, 1.0, 1.0),
        (5, 2) => Vec3::splat(f32::INFINITY),
        (6, 3) => Vec3::new(-4.0, 1.0, 1.0),
        _ => Vec3::splat(0.5),
    });
    let light = resolve(&ImageInfiniteLight::new(img), tilted());
    assert_eq!(light.tables.bad_texels, 2);
    assert_outputs_finite(&light, "NaN/Inf texels");
}

#[test]
fn bad_image_lights_are_errors() {
    let sky = test_sky(8, 4);
    let bad = [
        ImageInfiniteLight::new(Arc::new(RgbImage { width: 0, height: 0, pixels: vec![] })),
        ImageInfiniteLight::new(Arc::new(RgbImage { width: 4, height: 4, pixels: vec![Vec3::ONE; 15] })),
        ImageInfiniteLight { scale: -1.0, ..ImageInfiniteLight::new(sky.clone()) },
        ImageInfiniteLight { scale: f32::NAN, ..ImageInfiniteLight::new(sky.clone()) },
        ImageInfiniteLight { table_max_width: Some(0), ..ImageInfiniteLight::new(sky) },
    ];
    for light in bad {
        let err = light.resolve(&Transform::IDENTITY, SceneSphere::default()).expect_err("must be rejected");
        eprintln!("rejected: {err}");
    }
}

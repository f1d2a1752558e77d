//! The glTF BSDF: sampled directions follow the pdf (chi-square), pdfs integrate to the share of
//! valid samples, sampled weights average to the albedo integrated on a grid, the closed-form
//! peak and KHR_materials_specular's grazing term, metals sample no empty lobe, the bent shading
//! normal, and specular 0 or ior 1 leaves a pure Lambertian.

mod common;

use common::chi_square::assert_chi_square;
use common::lobe_grid::LobeGrid;
use glam::{Vec2, Vec3};
use kelvin::light::ColorQuery;
use kelvin::render::bsdf::bent_shading_normal;
use kelvin::render::material::Material;
use kelvin::rng::SplitMix64;
use rayon::prelude::*;

fn materials() -> Vec<(&'static str, Material)> {
    vec![
        ("lambert", Material::lambertian(Vec3::splat(0.7))),
        ("ior_1", Material { ior: 1.0, ..Default::default() }),
        ("plastic", Material { roughness: 0.4, ..Default::default() }),
        (
            "rough_metal",
            Material { metallic: 1.0, roughness: 0.8, base_color: Vec3::new(0.9, 0.6, 0.3), ..Default::default() },
        ),
        ("shiny_metal", Material { metallic: 1.0, roughness: 0.15, ..Default::default() }),
    ]
}

/// View directions at `degrees` from the normal, in the xz plane.
fn view(degrees: f32) -> Vec3 {
    let t = degrees.to_radians();
    Vec3::new(t.sin(), 0.0, t.cos())
}

/// The lobes at roughness 0.05-1 (perceptual): a metal (the specular lobe alone), a dielectric
/// (diffuse and specular mixed) and a Lambertian (diffuse alone), with their grids' width: the
/// specular lobe's scale in radians, about 4 alpha.
fn lobes() -> Vec<(String, Material, f64)> {
    let mut lobes = vec![("lambert".to_string(), Material::lambertian(Vec3::splat(0.7)), 1.0)];
    for roughness in [0.05f32, 0.3, 0.7, 1.0] {
        let c = (4.0 * roughness as f64 * roughness as f64).min(1.0);
        let metal = Material { metallic: 1.0, roughness, base_color: Vec3::new(0.9, 0.6, 0.3), ..Default::default() };
        lobes.push((format!("metal r={roughness}"), metal, c));
        lobes.push((format!("dielectric r={roughness}"), Material { roughness, ..Default::default() }, c));
    }
    lobes
}

/// A grid about the mirror direction of `wo` (local frame, z = normal), `c` its finest scale.
fn mirror_grid(wo: Vec3, c: f64) -> LobeGrid {
    LobeGrid::new(Vec3::new(-wo.x, -wo.y, wo.z), c, 40, 40)
}

/// pbrt-v4's bsdfs_test in spirit: every lobe's sampled directions, binned on a grid fine about
/// the mirror direction, follow the pdf integrated over each cell, and the share of samples that
/// do not fail (reflected below the horizon) is the pdf's integral. Hard cases:
/// roughness 0.05 (alpha 0.0025, a lobe a few milliradians wide) and views to 89 degrees, where
/// the visible-normal lobe is cut by the horizon.
#[test]
fn every_lobe_samples_directions_by_its_pdf_chi_square() {
    let views = [0.0f32, 30.0, 60.0, 80.0, 89.0];
    let cases: Vec<_> = lobes().into_iter().flat_map(|l| views.map(|v| (l.clone(), v))).collect();
    cases.par_iter().for_each(|((name, material, c), degrees)| {
        let bsdf = material.bsdf(Vec2::ZERO, Vec3::Z, ColorQuery::Rgb);
        let wo = view(*degrees);
        let grid = mirror_grid(wo, *c);
        let cells = grid.integrate_cells(24, Vec3::Z, 60, |wi| bsdf.pdf(wo, wi) as f64);
        let total: f64 = cells.iter().sum();
        let probs: Vec<f64> = cells.iter().map(|p| p / total).collect();
        let mut counts = vec![0u64; probs.len()];
        let (mut rng, n) = (SplitMix64::new(7 + *degrees as u64), 400_000);
        for _ in 0..n {
            if let Some(s) = bsdf.sample(wo, rng.f32(), rng.vec2()) {
                counts[grid.cell_of(s.wi)] += 1;
            }
        }
        // The samples that fail (reflected below the horizon) are those the pdf does not cover.
        let valid = counts.iter().sum::<u64>() as f64 / n as f64;
        let what = format!("{name} at {degrees} degrees");
        assert!((valid - total).abs() < 2e-3, "{what}: {valid} of the samples valid, the pdf integrates to {total}");
        let stat = assert_chi_square(&what, &counts, &probs);
        eprintln!("{name} at {degrees} deg: chi2 {stat:.0}, pdf integral {total:.4}");
    });
}

/// The white furnace of one BSDF: the mean of sampled weights f cos / pdf is the directional
/// albedo, the integral of f cos over the hemisphere on a grid (which never calls the sampler).
/// Roughness 0.1-1, metal and dielectric, views to 80 degrees.
#[test]
fn sampled_weights_average_to_the_directional_albedo_integrated_on_a_grid() {
    let mut cases = Vec::new();
    for roughness in [0.1f32, 0.3, 0.6, 1.0] {
        for metallic in [0.0f32, 1.0] {
            for degrees in [0.0f32, 45.0, 80.0] {
                cases.push((roughness, metallic, degrees));
            }
        }
    }
    cases.par_iter().for_each(|&(roughness, metallic, degrees)| {
        let material = Material { metallic, roughness, base_color: Vec3::ONE, ..Default::default() };
        let bsdf = material.bsdf(Vec2::ZERO, Vec3::Z, ColorQuery::Rgb);
        let wo = view(degrees);
        let grid = mirror_grid(wo, (4.0 * roughness as f64 * roughness as f64).min(1.0));
        let albedo: f64 =
            grid.integrate_cells(8, Vec3::Z, 40, |wi| bsdf.f(wo, wi).0[1] as f64 * wi.z.max(0.0) as f64).iter().sum();
        let mut rng = SplitMix64::new(3);
        let n = 200_000;
        let (mut sum, mut sum2) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let w = bsdf.sample(wo, rng.f32(), rng.vec2()).map_or(0.0, |s| (s.f.0[1] * s.wi.z / s.pdf) as f64);
            (sum, sum2) = (sum + w, sum2 + w * w);
        }
        let mean = sum / n as f64;
        let error = ((sum2 / n as f64 - mean * mean) / n as f64).sqrt();
        let what = format!("roughness {roughness} metallic {metallic} at {degrees} deg");
        eprintln!("{what}: sampled {mean:.5} +- {error:.5}, grid {albedo:.5}");
        assert!((mean - albedo).abs() < 4.0 * error + 1e-3 * albedo, "{what}: {mean} +- {error} vs {albedo}");
        // Single scattering loses energy; glTF's dielectric mix (1 - F(v.h)) diffuse plus F
        // specular does not conserve it at grazing views (1.35 at 80 degrees, roughness 0.1).
        assert!(metallic < 1.0 || albedo < 1.0 + 1e-3, "{what}: albedo {albedo}");
    });
}

/// glTF's alpha is roughness squared: head-on, a white metal's f(n, n) = D(n) V(n, n) =
/// 1 / (pi alpha^2) * 1 / 4 (height-correlated Smith, G = 1 there).
#[test]
fn a_white_metal_head_on_has_the_closed_form_peak_of_alpha_equal_to_roughness_squared() {
    for roughness in [0.2f32, 0.5, 0.8] {
        let material = Material { metallic: 1.0, roughness, base_color: Vec3::ONE, ..Default::default() };
        let f = material.bsdf(Vec2::ZERO, Vec3::Z, ColorQuery::Rgb).f(Vec3::Z, Vec3::Z).0[1];
        let alpha = roughness * roughness;
        let want = 0.25 / (std::f32::consts::PI * alpha * alpha);
        assert!((f / want - 1.0).abs() < 1e-5, "roughness {roughness}: {f} vs {want}");
    }
}

/// KHR_materials_specular scales F0 and the grazing reflectance F90 alike by its factor, so on a
/// black dielectric (no diffuse) the factor scales f by itself at every angle, grazing included.
#[test]
fn the_specular_factor_scales_the_grazing_reflectance_too() {
    let black = |specular| Material { base_color: Vec3::ZERO, roughness: 0.4, specular, ..Default::default() };
    let (full, half) = (black(1.0), black(0.5));
    for degrees in [0.0f32, 60.0, 85.0, 89.0] {
        let wo = view(degrees);
        let wi = Vec3::new(-wo.x, 0.0, wo.z);
        let f = |m: &Material| m.bsdf(Vec2::ZERO, Vec3::Z, ColorQuery::Rgb).f(wo, wi).0[1];
        let ratio = f(&half) / f(&full);
        assert!((ratio - 0.5).abs() < 1e-4, "at {degrees} deg: specular 0.5 reflects {ratio} of specular 1");
    }
}

/// A metal has no diffuse lobe, so none of its samples may go to one: a sharp metal's sampled
/// weights (F G2 / G1 with visible normals) stay near its albedo, none are wasted near zero.
#[test]
fn a_metal_spends_no_samples_on_an_empty_diffuse_lobe() {
    let material = Material { metallic: 1.0, roughness: 0.05, base_color: Vec3::ONE, ..Default::default() };
    let bsdf = material.bsdf(Vec2::ZERO, Vec3::Z, ColorQuery::Rgb);
    let wo = view(30.0);
    let mut rng = SplitMix64::new(4);
    let n = 100_000;
    let wasted = (0..n)
        .filter(|_| bsdf.sample(wo, rng.f32(), rng.vec2()).is_none_or(|s| s.f.0[1] * s.wi.z / s.pdf < 0.01))
        .count();
    assert!(wasted < n / 200, "{wasted} of {n} samples weigh under 1% (cosine samples off the lobe)");
}

/// The bent shading normal: where the mirror direction of the view about the shading normal
/// already leaves the surface it is kept; elsewhere it moves toward the geometric normal until
/// the mirror direction leaves at min(0.9 cos, 0.01), and the view is above it.
#[test]
fn a_bent_shading_normal_sees_the_view_and_reflects_it_above_the_surface() {
    let ng = Vec3::Z;
    let mut rng = SplitMix64::new(9);
    let mut bent = 0;
    for _ in 0..20_000 {
        let ns = (kelvin::sampling::sample_uniform_sphere(rng.vec2()) + 1.2 * ng).normalize();
        let wo = kelvin::sampling::sample_uniform_sphere(rng.vec2());
        let wo = Vec3::new(wo.x, wo.y, wo.z.abs().max(1e-4)).normalize();
        let n = bent_shading_normal(ns, ng, wo);
        let mirror_z = |n: Vec3| 2.0 * n.dot(wo) * n.dot(ng) - wo.z;
        let threshold = (0.9 * wo.z).min(0.01);
        assert!((n.length() - 1.0).abs() < 1e-5);
        if n == ns {
            assert!(mirror_z(ns) >= threshold);
            continue;
        }
        bent += 1;
        assert!(mirror_z(ns) < threshold, "a good normal was bent");
        assert!((mirror_z(n) - threshold).abs() < 2e-4, "{} vs {threshold}", mirror_z(n));
        assert!(n.dot(wo) > 0.0 && n.dot(ng) > 0.0);
        // It stays in the plane of the two normals.
        assert!(n.dot(ns.cross(ng).normalize()).abs() < 1e-4);
    }
    assert!(bent > 1000, "{bent} bent");
}

#[test]
fn pdf_integrates_to_the_probability_of_a_valid_sample() {
    // Microfacet samples that reflect below the horizon are rejected, so the pdf integrates to
    // the fraction of samples that succeed (1 for the diffuse lobe).
    let mut rng = SplitMix64::new(2);
    for (name, m) in materials() {
        let bsdf = m.bsdf(Vec2::ZERO, Vec3::Z, ColorQuery::Rgb);
        let wo = Vec3::new(0.4, 0.1, 0.9).normalize();
        let n = 400_000;
        let (mut pdf_sum, mut refl) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let wi = kelvin::sampling::sample_uniform_sphere(rng.vec2());
            let inv = 1.0 / kelvin::sampling::uniform_sphere_pdf() as f64;
            pdf_sum += bsdf.pdf(wo, wi) as f64 * inv;
            refl += bsdf.f(wo, wi).0[1] as f64 * wi.z.max(0.0) as f64 * inv;
        }
        let (pdf_int, albedo) = (pdf_sum / n as f64, refl / n as f64);
        let valid = (0..n).filter(|_| bsdf.sample(wo, rng.f32(), rng.vec2()).is_some()).count() as f64 / n as f64;
        eprintln!("{name}: integral of pdf {pdf_int:.4}, valid samples {valid:.4}, directional albedo {albedo:.4}");
        assert!((pdf_int - valid).abs() < 0.03, "{name}: pdf integrates to {pdf_int}, {valid} of samples valid");
        assert!(albedo < 1.0 + 0.02, "{name}: albedo {albedo}");
    }
}

#[test]
fn specular_zero_or_ior_one_is_pure_lambertian() {
    for m in [Material { specular: 0.0, ..Default::default() }, Material { ior: 1.0, ..Default::default() }] {
        let bsdf = m.bsdf(Vec2::ZERO, Vec3::Z, ColorQuery::Rgb);
        assert!(!bsdf.has_specular());
        let f = bsdf.f(Vec3::new(0.0, 0.6, 0.8), Vec3::new(0.3, 0.0, 0.95).normalize());
        assert!((f.0[0] - 0.8 / std::f32::consts::PI).abs() < 1e-6);
    }
    assert!(Material::default().bsdf(Vec2::ZERO, Vec3::Z, ColorQuery::Rgb).has_specular());
}

#[test]
fn uniform_bsdf_is_the_bsdf_of_every_point_and_textured_materials_have_none() {
    use kelvin::sampling::Frame;
    let n = Vec3::new(-0.2, 0.4, 0.9).normalize();
    let (wo, wi) = (Vec3::new(0.1, 0.3, 0.95).normalize(), Vec3::new(-0.5, 0.2, 0.8).normalize());
    for (name, m) in materials() {
        let per_point = m.bsdf(Vec2::new(0.3, 0.7), n, ColorQuery::Rgb);
        let uniform = m.uniform_rgb_bsdf().expect("untextured");
        let placed = kelvin::render::bsdf::Bsdf { frame: Frame::from_z(n), ..uniform };
        assert_eq!(placed.f(wo, wi).0, per_point.f(wo, wi).0, "{name}");
        assert_eq!(placed.pdf(wo, wi), per_point.pdf(wo, wi), "{name}");
    }
    let image = kelvin::scene::image::RgbImage { width: 1, height: 1, pixels: vec![Vec3::ONE] };
    let textured = Material { base_color_texture: Some(std::sync::Arc::new(image)), ..Default::default() };
    assert!(textured.uniform_rgb_bsdf().is_none());
}

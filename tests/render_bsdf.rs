//! The glTF BSDF: sampled pdfs match the pdf function, pdfs integrate to 1, energy is conserved,
//! and specular 0 or ior 1 leaves a pure Lambertian.

use glam::{Vec2, Vec3};
use kelvin::light::ColorQuery;
use kelvin::render::material::Material;
use kelvin::rng::SplitMix64;

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

#[test]
fn sample_pdf_matches_pdf_function() {
    let mut rng = SplitMix64::new(1);
    let n = Vec3::new(0.3, 0.9, 0.1).normalize();
    for (name, m) in materials() {
        let bsdf = m.bsdf(Vec2::ZERO, n, ColorQuery::Rgb);
        let wo = (n + Vec3::new(0.5, 0.0, 0.2)).normalize();
        for _ in 0..10_000 {
            if let Some(s) = bsdf.sample(wo, rng.f32(), rng.vec2()) {
                let p = bsdf.pdf(wo, s.wi);
                // f32 round trip of the half vector (sampled h vs normalize(wo + wi)) for sharp lobes.
                assert!((s.pdf / p - 1.0).abs() < 2e-3, "{name}: {} vs {p}", s.pdf);
                let f = bsdf.f(wo, s.wi);
                assert!((0..3).all(|k| (s.f.0[k] - f.0[k]).abs() <= 2e-3 * f.0[k].abs().max(1.0)), "{name}");
            }
        }
    }
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

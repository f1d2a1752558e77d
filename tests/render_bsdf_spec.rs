//! The glTF BSDF's `f` against the glTF 2.0 specification's BRDF (appendix B, with
//! KHR_materials_ior and KHR_materials_specular's Fresnel), written out here in f64 from the spec
//! and not from the crate's functions: Lambertian diffuse, GGX D with alpha = roughness^2,
//! height-correlated Smith visibility and Schlick's Fresnel, mixed by `fresnel_mix` and
//! `conductor_fresnel` and blended by metallic. This is the check of `f` that the furnace test
//! (render_bsdf.rs, which integrates the same `f` it samples) cannot make.

use glam::{Vec2, Vec3};
use kelvin::light::ColorQuery;
use kelvin::render::material::Material;

/// Relative tolerance of a point evaluation, 5e-4: the crate evaluates in f32, and a sharp lobe's
/// D is steep in the half vector where its angle is near alpha (d ln D / d sin = 2 / alpha, 2000
/// at alpha 1e-3), so the half vector's f32 rounding (6e-8) moves D by up to ~1.5e-4 there
/// (measured: 1.48e-4 just off the peak at roughness 0.032). About a tilted normal the crate's
/// change of frame rounds local coordinates by ~6e-8 too, which a grazing mirror pair at alpha
/// 1e-3 amplifies (measured up to 4.4e-3): `TILTED_TOLERANCE`. A D 3% off fails either.
const TOLERANCE: f64 = 5e-4;
const TILTED_TOLERANCE: f64 = 1e-2;

/// The spec's parameters of one material (the defaults ior 1.5 and specular 1 give f0 = 0.04).
#[derive(Clone, Copy, Debug)]
struct Params {
    base: [f64; 3],
    metallic: f64,
    roughness: f64,
    ior: f64,
    specular: f64,
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn normalize(a: [f64; 3]) -> [f64; 3] {
    let l = dot(a, a).sqrt();
    a.map(|x| x / l)
}

fn f64s(v: Vec3) -> [f64; 3] {
    [v.x as f64, v.y as f64, v.z as f64]
}

/// glTF 2.0 appendix B: f(V, L) for unit vectors toward the viewer `v` and the light `l` about
/// the normal `n`, per RGB channel; 0 unless both are above the surface.
fn spec_brdf(p: Params, n: [f64; 3], v: [f64; 3], l: [f64; 3]) -> [f64; 3] {
    let (n_l, n_v) = (dot(n, l), dot(n, v));
    if n_l <= 0.0 || n_v <= 0.0 {
        return [0.0; 3];
    }
    let h = normalize([l[0] + v[0], l[1] + v[1], l[2] + v[2]]);
    let (n_h, v_h) = (dot(n, h), dot(v, h).abs().min(1.0));
    let alpha = p.roughness * p.roughness;
    let a2 = alpha * alpha;
    // D_GGX = alpha^2 chi+(N.H) / (pi ((N.H)^2 (alpha^2 - 1) + 1)^2).
    let d = if n_h > 0.0 { a2 / (std::f64::consts::PI * (n_h * n_h * (a2 - 1.0) + 1.0).powi(2)) } else { 0.0 };
    // V_GGX = G / (4 |N.L| |N.V|), height-correlated:
    // 0.5 / (N.L sqrt((N.V)^2 (1 - alpha^2) + alpha^2) + N.V sqrt((N.L)^2 (1 - alpha^2) + alpha^2)).
    let vis = 0.5 / (n_l * (n_v * n_v * (1.0 - a2) + a2).sqrt() + n_v * (n_l * n_l * (1.0 - a2) + a2).sqrt());
    let specular_brdf = vis * d;
    let tail = (1.0 - v_h).powi(5);
    // fresnel_mix with KHR_materials_ior's f0 and KHR_materials_specular's weight (specular
    // colour 1): (1 - weight fr) base + weight fr layer, fr = f0 + (1 - f0) (1 - |V.H|)^5.
    let f0 = (((1.0 - p.ior) / (1.0 + p.ior)).powi(2)).min(1.0);
    let fr = p.specular * (f0 + (1.0 - f0) * tail);
    std::array::from_fn(|k| {
        let c = p.base[k];
        let diffuse_brdf = c / std::f64::consts::PI;
        let dielectric = (1.0 - fr) * diffuse_brdf + fr * specular_brdf;
        // conductor_fresnel: specular_brdf (c + (1 - c) (1 - |V.H|)^5).
        let metal = specular_brdf * (c + (1.0 - c) * tail);
        (1.0 - p.metallic) * dielectric + p.metallic * metal
    })
}

/// The crate's f for `p` at shading normal `n`, RGB.
fn crate_f(p: Params, n: Vec3, wo: Vec3, wi: Vec3) -> [f64; 3] {
    let material = Material {
        base_color: Vec3::new(p.base[0] as f32, p.base[1] as f32, p.base[2] as f32),
        metallic: p.metallic as f32,
        roughness: p.roughness as f32,
        ior: p.ior as f32,
        specular: p.specular as f32,
        ..Default::default()
    };
    let f = material.bsdf(Vec2::ZERO, n, ColorQuery::Rgb).f(wo, wi);
    [f.0[0] as f64, f.0[1] as f64, f.0[2] as f64]
}

/// A unit direction at `theta` degrees from `n` and azimuth `phi` degrees about it.
fn direction(n: Vec3, theta: f32, phi: f32) -> Vec3 {
    let frame = kelvin::sampling::Frame::from_z(n);
    let (t, p) = (theta.to_radians(), phi.to_radians());
    frame.from_local(Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())).normalize()
}

/// Asserts the crate's f equals the spec's within `TOLERANCE` (`TILTED_TOLERANCE` about a normal
/// other than +z; 0 where the spec's is);
/// returns the largest relative error.
fn check(what: &str, p: Params, n: Vec3, wo: Vec3, wi: Vec3) -> f64 {
    let tolerance = if n == Vec3::Z { TOLERANCE } else { TILTED_TOLERANCE };
    // The spec's N is unit: an f32 unit vector's length is 1 +- 6e-8, which at alpha 1e-3
    // (alpha^2 1e-6) moves 1 - (N.H)^2, so the spec's D at its peak, by tens of percent. V and L
    // are used as given (H is normalised; N.L and N.V move by 6e-8 of themselves).
    let (got, want) = (crate_f(p, n, wo, wi), spec_brdf(p, normalize(f64s(n)), f64s(wo), f64s(wi)));
    let mut worst = 0.0f64;
    for k in 0..3 {
        // Zero (and the spec's 1e-40 of f64 rounding in a Fresnel tail whose V.H is 1 in f32).
        if want[k] < 1e-12 {
            assert!(got[k] < 1e-12, "{what} {p:?} wo {wo} wi {wi} channel {k}: f = {} where the spec's is 0", got[k]);
            continue;
        }
        let rel = (got[k] / want[k] - 1.0).abs();
        assert!(
            rel < tolerance,
            "{what} {p:?} wo {wo} wi {wi} channel {k}: f = {:e}, the spec's {:e} (relative error {rel:.2e})",
            got[k],
            want[k]
        );
        worst = worst.max(rel);
    }
    worst
}

fn materials() -> Vec<Params> {
    let colours = [[1.0, 1.0, 1.0], [0.0, 0.0, 0.0], [0.9, 0.1, 0.3]];
    // (ior, specular): glTF's defaults, water with half the specular, a diamond's ior.
    let fresnel = [(1.5, 1.0), (1.33, 0.5), (2.4, 1.0)];
    let mut all = Vec::new();
    // Roughness 0.032 is the smallest kelvin keeps (alpha = 1.02e-3, above its floor of 1e-3).
    for roughness in [0.032, 0.1, 0.3, 0.5, 0.8, 1.0] {
        for metallic in [0.0, 0.5, 1.0] {
            for base in colours {
                for (ior, specular) in fresnel {
                    all.push(Params { base, metallic, roughness, ior, specular });
                }
            }
        }
    }
    all
}

/// Point evaluations over views and lights from the normal to 89.9 degrees and azimuths from
/// the same side to the mirror side, for roughness 0.032-1, metallic 0, 0.5 and 1, white, black
/// and coloured bases, and three Fresnel settings, about +z and about a tilted normal.
#[test]
fn f_equals_the_gltf_spec_brdf_over_directions_and_materials() {
    let thetas = [0.0f32, 20.0, 45.0, 75.0, 89.5, 89.9];
    let phis = [0.0f32, 45.0, 90.0, 135.0, 180.0];
    let normals = [Vec3::Z, Vec3::new(0.3, -0.5, 0.8).normalize()];
    let (mut count, mut worst) = (0usize, 0.0f64);
    for n in normals {
        for p in materials() {
            for &to in &thetas {
                for &ti in &thetas {
                    for &phi in &phis {
                        let (wo, wi) = (direction(n, to, 0.0), direction(n, ti, phi));
                        worst = worst.max(check("grid", p, n, wo, wi));
                        count += 1;
                    }
                }
            }
        }
    }
    eprintln!("{count} evaluations: largest relative error {worst:.2e}");
}

/// The hard cases, each named: the peak of the sharpest lobe and just off it, grazing views and
/// lights, retro-reflection at grazing, the flat D of roughness 1, a specular-only black
/// dielectric, and directions below the surface (f = 0).
#[test]
fn f_equals_the_gltf_spec_brdf_in_the_hard_cases() {
    let n = Vec3::Z;
    let material = |roughness, metallic, base| Params { base, metallic, roughness, ior: 1.5, specular: 1.0 };
    let mirror = |wo: Vec3| Vec3::new(-wo.x, -wo.y, wo.z);
    let coloured = [0.9, 0.1, 0.3];
    let sharp = material(0.032, 1.0, coloured);
    for view in [0.0f32, 30.0, 60.0, 85.0] {
        let wo = direction(n, view, 0.0);
        // Roughness 0.032 (alpha 1.02e-3) at the mirror direction: D = 1 / (pi alpha^2) ~ 3e5.
        check("sharp lobe's peak", sharp, n, wo, mirror(wo));
        check("sharp dielectric's peak", material(0.032, 0.0, coloured), n, wo, mirror(wo));
        // Just off the peak (the light 0.1-1 degree from the mirror direction, the half vector
        // half that, about alpha to 8 alpha), where D falls by orders of magnitude.
        for off in [0.05f32, 0.1, 0.2, 0.5] {
            check("sharp lobe off its peak", sharp, n, wo, direction(n, view + 2.0 * off, 180.0));
            check("sharp lobe off its peak (azimuth)", sharp, n, wo, direction(n, view.max(1.0), 180.0 + off));
        }
    }
    // Grazing view and light (cosines 1.7e-3 and 8.7e-3) on every roughness and metallic.
    for roughness in [0.032, 0.3, 1.0] {
        for metallic in [0.0, 1.0] {
            let p = material(roughness, metallic, coloured);
            let wo = direction(n, 89.9, 0.0);
            check("grazing view, grazing mirror light", p, n, wo, mirror(wo));
            check("grazing view, grazing light at 89.5", p, n, wo, direction(n, 89.5, 180.0));
            check("grazing view, light head-on", p, n, wo, n);
            check("grazing view, grazing light at 90 degrees azimuth", p, n, wo, direction(n, 89.5, 90.0));
            // Retro-reflection at grazing: wo = wi, V.H = 1, the Fresnel tail vanishes.
            check("grazing retro-reflection", p, n, wo, wo);
            check("head-on view and light", p, n, n, n);
        }
    }
    // Roughness 1: alpha 1, D = 1 / pi everywhere.
    let rough = material(1.0, 0.5, [1.0, 1.0, 1.0]);
    for (a, b) in [(0.0f32, 80.0f32), (60.0, 60.0), (89.9, 10.0)] {
        check("roughness 1 (flat D)", rough, n, direction(n, a, 0.0), direction(n, b, 135.0));
    }
    // A black dielectric: no diffuse, only the Fresnel-weighted specular lobe.
    let black = material(0.4, 0.0, [0.0, 0.0, 0.0]);
    check("black dielectric (specular only)", black, n, direction(n, 70.0, 0.0), direction(n, 70.0, 180.0));
    // Below the surface the spec's BRDF is 0: the light below, the view below, both.
    let p = material(0.5, 0.5, coloured);
    let below = |d: Vec3| Vec3::new(d.x, d.y, -d.z);
    let (wo, wi) = (direction(n, 40.0, 0.0), direction(n, 50.0, 180.0));
    check("light below the surface", p, n, wo, below(wi));
    check("view below the surface", p, n, below(wo), wi);
    check("view and light below the surface", p, n, below(wo), below(wi));
    check("light exactly in the surface plane", p, n, wo, Vec3::new(-1.0, 0.0, 0.0));
}

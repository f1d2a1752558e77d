//! Shading normals where they meet back faces: a surface seen from behind keeps its smooth normal
//! (turned to the viewer with the geometric one), whether the file's normals agree with the
//! triangles' winding or not. Every figure is a closed form of a point light over a Lambertian
//! surface: rho/pi I cos(theta_s) / d^2, theta_s measured from the shading normal.

use bevy_ecs::prelude::*;
use glam::Vec3;
use kelvin::geometry::{Mesh, Transform};
use kelvin::light::PointLight;
use kelvin::render::camera::Camera;
use kelvin::render::material::Material;
use kelvin::render::renderer::{Integrator, RenderOptions, render};
use kelvin::systems::LightingPlugin;

const RHO: f32 = 0.5;
const CANDELA: f32 = 100.0;

fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// A world with `mesh` (Lambertian), a point light at `light` and a narrow camera at `eye`
/// looking along `dir`; returns the luminance of the one pixel.
fn render_one_pixel(mesh: Mesh, light: Vec3, eye: Vec3, dir: Vec3) -> f32 {
    let mut world = World::new();
    let mut schedule = Schedule::default();
    LightingPlugin::build(&mut world, &mut schedule);
    world.spawn((mesh, Transform::IDENTITY, Material::lambertian(Vec3::splat(RHO))));
    world.spawn((PointLight::candela(CANDELA), Transform::from_translation(light)));
    let up = if dir.cross(Vec3::Y).length() > 1e-3 { Vec3::Y } else { Vec3::Z };
    world.spawn((Camera { yfov: 1e-4 }, Transform::from_translation(eye).looking_to(dir, up)));
    let opts = RenderOptions { integrator: Integrator::Direct, ..RenderOptions::direct(1, 1, 4) };
    luminance(render(&mut world, &mut schedule, &opts, |_| {}).0.pixel(0, 0))
}

/// A 4 x 4 m sheet at y = 0 wound with its geometric normal `+Y` (or `-Y` when `inverted`) and
/// every vertex normal `ns` (so the interpolated normal is `ns` everywhere).
fn sheet(ns: Vec3, inverted: bool) -> Mesh {
    let p = vec![
        Vec3::new(-2.0, 0.0, -2.0),
        Vec3::new(2.0, 0.0, -2.0),
        Vec3::new(2.0, 0.0, 2.0),
        Vec3::new(-2.0, 0.0, 2.0),
    ];
    // Counter-clockwise seen from +Y: (0, 3, 2), (0, 2, 1) has normal +Y.
    let indices = if inverted { vec![0, 1, 2, 0, 2, 3] } else { vec![0, 3, 2, 0, 2, 1] };
    Mesh::new(p, indices).unwrap().with_normals(vec![ns; 4]).unwrap()
}

/// The hard case: a sheet whose smooth normals lean 30 degrees, lit and seen straight on from
/// either side, its file normals agreeing with the winding or not. A back-face hit kept the flat
/// normal (cos 1 instead of cos 30: 15% bright), an inconsistent normal seen from behind was kept
/// on the wrong side.
#[test]
fn a_two_sided_smooth_sheet_shades_with_its_smooth_normal_from_either_side() {
    let lean = 30f32.to_radians();
    let ns = Vec3::new(lean.sin(), lean.cos(), 0.0);
    let h = 2.0;
    let want = RHO / std::f32::consts::PI * CANDELA * lean.cos() / (h * h);
    for side in [1.0f32, -1.0] {
        for (file_ns, inverted, what) in [
            (ns, false, "normals agree with the winding"),
            (-ns, true, "winding and normals both turned"),
            (-ns, false, "normals against the winding"),
            (ns, true, "winding against the normals"),
        ] {
            let light = Vec3::new(0.0, side * h, 0.0);
            let eye = Vec3::new(0.0, side * 1.0, 0.0);
            let got = render_one_pixel(sheet(file_ns, inverted), light, eye, Vec3::new(0.0, -side, 0.0));
            let face = if side > 0.0 { "from +Y" } else { "from -Y" };
            eprintln!("sheet {face}, {what}: {got:.5} vs {want:.5}");
            assert!((got / want - 1.0).abs() < 1e-3, "sheet {face}, {what}: {got} vs {want}");
        }
    }
}

/// A coarse unit UV sphere (8 segments, 4 rings) wound with outward geometric normals, with
/// vertex normals v / |v|: the interpolated normal at any point p of a face is then p / |p|.
fn coarse_sphere() -> (Vec<Vec3>, Vec<u32>) {
    let (segments, rings) = (8u32, 4u32);
    let mut p = vec![Vec3::Y];
    for r in 1..rings {
        let theta = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..segments {
            let phi = std::f32::consts::TAU * s as f32 / segments as f32;
            p.push(Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin()));
        }
    }
    p.push(Vec3::NEG_Y);
    let ring = |r: u32, s: u32| 1 + (r - 1) * segments + s % segments;
    let bottom = p.len() as u32 - 1;
    let mut indices = Vec::new();
    for s in 0..segments {
        indices.extend([0, ring(1, s + 1), ring(1, s)]);
        for r in 1..rings - 1 {
            let (a, b, c, d) = (ring(r, s), ring(r, s + 1), ring(r + 1, s + 1), ring(r + 1, s));
            indices.extend([a, b, c, a, c, d]);
        }
        indices.extend([bottom, ring(rings - 1, s), ring(rings - 1, s + 1)]);
    }
    (p, indices)
}

/// Hard case: a smooth sphere seen from inside, lit by a point at its centre. Every hit is a back
/// face; the smooth normal is radial, so cos = 1 and the pixel is rho/pi I / |p|^2 at the hit p.
/// Near a vertex of the coarse sphere the flat normal leans about 20 degrees from the radial one.
#[test]
fn a_smooth_sphere_seen_from_inside_shades_with_its_smooth_normals() {
    let (p, indices) = coarse_sphere();
    let triangles: Vec<[Vec3; 3]> =
        indices.chunks(3).map(|t| [p[t[0] as usize], p[t[1] as usize], p[t[2] as usize]]).collect();
    let mesh =
        Mesh::new(p.clone(), indices.clone()).unwrap().with_normals(p.iter().map(|v| v.normalize()).collect()).unwrap();
    // Aim near a vertex of a side face and of a polar face.
    for t in [triangles[1], triangles[0], triangles[5]] {
        let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize();
        assert!(n.dot(t[0]) > 0.0, "the test sphere is wound outward");
        let dir = (0.9 * t[0] + 0.05 * t[1] + 0.05 * t[2]).normalize();
        let hit = dir * n.dot(t[0]) / n.dot(dir);
        let flat_cos = n.dot(dir);
        let want = RHO / std::f32::consts::PI * CANDELA / hit.length_squared();
        let eye = 1e-3 * dir;
        let got = render_one_pixel(mesh.clone(), Vec3::ZERO, eye, dir);
        eprintln!(
            "inside the sphere toward {dir}: {got:.5} vs {want:.5} (the flat normal would give cos {flat_cos:.4})"
        );
        assert!((got / want - 1.0).abs() < 2e-3, "toward {dir}: {got} vs {want}");
    }
}

/// Hard case: a grazing view of a sheet whose smooth normals lean 60 degrees away from the eye,
/// so the view is below the shading hemisphere (wo . ns = -0.71) though above the surface. The
/// camera pass bends the shading normal toward the geometric one until the view's mirror
/// direction leaves the surface (`bent_shading_normal`); without it the pixel was black. The
/// figure is the closed form with the bent normal, whose own property `render_bsdf` tests.
#[test]
fn a_grazing_view_below_the_smooth_normal_shades_with_the_bent_normal() {
    let (lean, grazing) = (60f32.to_radians(), 75f32.to_radians());
    let ns = Vec3::new(lean.sin(), lean.cos(), 0.0);
    let wo = Vec3::new(-grazing.sin(), grazing.cos(), 0.0);
    assert!(wo.dot(ns) < -0.7 && wo.y > 0.25, "the view is below the smooth normal, above the sheet");
    let bent = kelvin::render::bsdf::bent_shading_normal(ns, Vec3::Y, wo);
    assert!(bent.dot(wo) > 0.0, "the bent normal sees the view");
    let h = 2.0;
    let light = Vec3::new(0.0, h, 0.0);
    let want = RHO / std::f32::consts::PI * CANDELA * bent.dot(Vec3::Y) / (h * h);
    let got = render_one_pixel(sheet(ns, false), light, 1.5 * wo, -wo);
    eprintln!("grazing view below the smooth normal: {got:.5} vs {want:.5}");
    assert!((got / want - 1.0).abs() < 1e-3, "{got} vs {want}");
}

//! Writes the many-lights scaling scene (`kelvin::scenes::spawn_scaling_scene`) as a glTF 2.0 binary file, for
//! the render suite (`kelvin bench render`) and for other renderers (bench/mitsuba/).
//! `cargo run --release --example export_scaling_gltf [N] [OUT.glb] [SEED]`
//! (defaults: 10000, tests/data/gltf/bench/scaling_10k.glb, seed 1 as `kelvin bench lights`).
//!
//! The scene is spawned by `spawn_scaling_scene` and read back from the world, so the layout is
//! the generator's own: every light's position, orientation, cone angles, amount and colour, the
//! ground and each sphere's centre and radius. What glTF cannot hold is converted:
//! - lumens become candela as kelvin converts them (point: lm / 4 pi; spot: lm over the solid
//!   angle of its smoothstep falloff, 2 pi ((1 - cos inner) + (cos inner - cos outer) / 2));
//! - a blackbody spectrum becomes its linear sRGB colour (`srgb_normalized`), written as `color`
//!   = rgb / max(rgb) with the intensity divided by that colour's luminance, so that glTF's
//!   intensity x colour luminance is the light's candela;
//! - the analytic ground rectangle becomes a two-triangle quad, and each analytic sphere an
//!   instance (node translation and uniform scale) of one unit UV sphere of 16 x 8 segments
//!   (224 triangles, smooth normals);
//! - geometry without a material gets kelvin's default (`Material::default()`: base colour 0.8,
//!   metallic 0, roughness 0.5, specular 1, ior 1.5) as an explicit glTF material.
//!
//! The scene has no camera; the file gets one 30 m over the ground looking along -Z over the lit
//! square (a street-level view where only the nearby lights count).

use std::f32::consts::PI;
use std::path::PathBuf;

use bevy_ecs::prelude::*;
use glam::{Quat, Vec3};
use kelvin::geometry::{Rectangle, Sphere, Transform};
use kelvin::light::{Amount, PointLight, SpotLight};
use kelvin::spectrum::Spectrum;
use serde_json::{Value, json};

/// Segments of the unit sphere that stands in for each analytic sphere.
const SLICES: usize = 16;
const STACKS: usize = 8;

/// The binary chunk and the JSON index lists under construction.
#[derive(Default)]
struct Buffers {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Buffers {
    fn view(&mut self, bytes: &[u8], target: u32) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        self.views
            .push(json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len(), "target": target}));
        self.bin.extend_from_slice(bytes);
        self.views.len() - 1
    }

    /// POSITION, NORMAL and u16 indices; returns the primitive's JSON.
    fn primitive(&mut self, positions: &[Vec3], normals: &[Vec3], indices: &[u16], material: usize) -> Value {
        let f32s = |v: &[Vec3]| v.iter().flat_map(|p| p.to_array()).flat_map(f32::to_le_bytes).collect::<Vec<u8>>();
        let (min, max) =
            positions.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
        let view = self.view(&f32s(positions), 34962);
        self.accessors
            .push(json!({"bufferView": view, "componentType": 5126, "count": positions.len(), "type": "VEC3",
            "min": min.to_array(), "max": max.to_array()}));
        let pos = self.accessors.len() - 1;
        let view = self.view(&f32s(normals), 34962);
        self.accessors.push(json!({"bufferView": view, "componentType": 5126, "count": normals.len(), "type": "VEC3"}));
        let nrm = self.accessors.len() - 1;
        let bytes: Vec<u8> = indices.iter().flat_map(|i| i.to_le_bytes()).collect();
        let view = self.view(&bytes, 34963);
        self.accessors
            .push(json!({"bufferView": view, "componentType": 5123, "count": indices.len(), "type": "SCALAR"}));
        json!({"attributes": {"POSITION": pos, "NORMAL": nrm}, "indices": self.accessors.len() - 1, "material": material})
    }
}

/// A unit UV sphere, counter-clockwise outward: one triangle per cell in the polar rings, two elsewhere.
fn unit_sphere() -> (Vec<Vec3>, Vec<u16>) {
    let mut positions = Vec::new();
    for i in 0..=STACKS {
        let theta = PI * i as f32 / STACKS as f32;
        for j in 0..=SLICES {
            let phi = 2.0 * PI * j as f32 / SLICES as f32;
            let p = match i {
                0 => Vec3::Y,
                _ if i == STACKS => Vec3::NEG_Y,
                _ => Vec3::new(theta.sin() * phi.cos(), theta.cos(), -theta.sin() * phi.sin()),
            };
            positions.push(p);
        }
    }
    let row = SLICES + 1;
    let mut indices = Vec::new();
    for i in 0..STACKS {
        for j in 0..SLICES {
            let (a, b, c, d) = (i * row + j, i * row + j + 1, (i + 1) * row + j, (i + 1) * row + j + 1);
            if i != 0 {
                indices.extend([a, c, b]);
            }
            if i != STACKS - 1 {
                indices.extend([b, c, d]);
            }
        }
    }
    for t in indices.chunks(3) {
        let (a, b, c) = (positions[t[0]], positions[t[1]], positions[t[2]]);
        assert!((b - a).cross(c - a).dot(a + b + c) > 0.0, "sphere triangle faces inward");
    }
    (positions, indices.into_iter().map(|i| i as u16).collect())
}

/// Candela of a light given in lumens or candela (`kelvin::light`'s conversions).
fn candela(amount: Amount, solid_angle: f32) -> f32 {
    match amount {
        Amount::Candela(cd) => cd,
        Amount::Lumens(lm) => lm / solid_angle,
        other => panic!("the scaling scene's lights are photometric: {other:?}"),
    }
}

/// glTF `color` (max component 1) and the factor the intensity takes: 1 / its luminance, with the
/// Rec. 709 weights kelvin's import multiplies the intensity by (`scene::spawn`), so that the
/// imported light has the scene's candela.
fn colour(spectrum: &Spectrum) -> ([f32; 3], f32) {
    let rgb = spectrum.srgb_normalized().as_vec3();
    assert!(rgb.min_element() >= 0.0, "colour {rgb} outside sRGB");
    let color = rgb / rgb.max_element();
    (color.to_array(), 1.0 / color.dot(Vec3::new(0.2126, 0.7152, 0.0722)))
}

/// An f32 as the shortest decimal that reads back as the same f32 (serde_json would print the
/// f64 widening, twice as long).
fn num(v: f32) -> Value {
    json!(v.to_string().parse::<f64>().expect("a finite f32"))
}

fn nums(v: &[f32]) -> Value {
    Value::Array(v.iter().map(|&x| num(x)).collect())
}

/// A node's translation, and its rotation and scale where they are not the identity.
fn node_transform(t: &Transform) -> Value {
    let mut node = json!({"translation": nums(&t.translation.to_array())});
    if t.rotation != Quat::IDENTITY {
        node["rotation"] = nums(&t.rotation.to_array());
    }
    if t.scale != Vec3::ONE {
        node["scale"] = nums(&t.scale.to_array());
    }
    node
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let n: usize = args.first().map(|a| a.parse().expect("N: a number of lights")).unwrap_or(10_000);
    let out =
        PathBuf::from(args.get(1).cloned().unwrap_or_else(|| {
            concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/gltf/bench/scaling_10k.glb").to_string()
        }));
    let seed: u64 = args.get(2).map(|a| a.parse().expect("SEED: a number")).unwrap_or(1);

    let mut world = World::new();
    let scene = kelvin::scenes::spawn_scaling_scene(&mut world, n, seed);

    let mut buffers = Buffers::default();
    let mut nodes: Vec<Value> = Vec::new();
    let mut lights: Vec<Value> = Vec::new();
    // kelvin's Material::default() (what the scene's geometry renders with).
    let materials = json!([{"name": "kelvin default", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1.0],
        "metallicFactor": 0.0, "roughnessFactor": 0.5}}]);

    for &e in &scene.lights {
        let t = world.get::<Transform>(e).expect("a light's transform");
        let (light, node_name) = if let Some(p) = world.get::<PointLight>(e) {
            let (color, k) = colour(&p.spectrum);
            let cd = candela(p.amount, 4.0 * PI) * k;
            (json!({"type": "point", "color": nums(&color), "intensity": num(cd)}), "point")
        } else {
            let s = world.get::<SpotLight>(e).expect("a point or spot light");
            let (ci, co) = (s.inner_angle.cos(), s.outer_angle.cos());
            let (color, k) = colour(&s.spectrum);
            let cd = candela(s.amount, 2.0 * PI * ((1.0 - ci) + (ci - co) / 2.0)) * k;
            let spot = json!({"innerConeAngle": num(s.inner_angle), "outerConeAngle": num(s.outer_angle)});
            (json!({"type": "spot", "color": nums(&color), "intensity": num(cd), "spot": spot}), "spot")
        };
        lights.push(light);
        let mut node = node_transform(t);
        node["name"] = json!(format!("{node_name}{}", lights.len() - 1));
        node["extensions"] = json!({"KHR_lights_punctual": {"light": lights.len() - 1}});
        nodes.push(node);
    }

    let mut meshes: Vec<Value> = Vec::new();
    // The ground: the rectangle's corners in its local XY plane (front +Z), counter-clockwise from the front.
    {
        let rect = world.get::<Rectangle>(scene.ground).expect("the ground rectangle");
        let t = world.get::<Transform>(scene.ground).expect("the ground's transform");
        let h = rect.half_size;
        let local = [
            Vec3::new(-h.x, -h.y, 0.0),
            Vec3::new(h.x, -h.y, 0.0),
            Vec3::new(h.x, h.y, 0.0),
            Vec3::new(-h.x, h.y, 0.0),
        ];
        let normal = (t.rotation * Vec3::Z).normalize();
        let positions: Vec<Vec3> = local.iter().map(|&p| t.translation + t.rotation * (t.scale * p)).collect();
        assert!((positions[1] - positions[0]).cross(positions[2] - positions[0]).dot(normal) > 0.0);
        let prim = buffers.primitive(&positions, &[normal; 4], &[0, 1, 2, 0, 2, 3], 0);
        meshes.push(json!({"name": "ground", "primitives": [prim]}));
        nodes.push(json!({"name": "ground", "mesh": meshes.len() - 1}));
    }
    // The spheres: one unit mesh, one node each.
    let (positions, indices) = unit_sphere();
    let prim = buffers.primitive(&positions, &positions, &indices, 0);
    meshes.push(json!({"name": "unit sphere", "primitives": [prim]}));
    let sphere_mesh = meshes.len() - 1;
    let mut q = world.query::<(&Sphere, &Transform)>();
    let mut spheres = 0;
    for (s, t) in q.iter(&world) {
        assert_eq!(t.rotation, Quat::IDENTITY);
        let scale = t.scale * s.radius;
        nodes.push(json!({"name": format!("sphere{spheres}"), "mesh": sphere_mesh,
            "translation": nums(&t.translation.to_array()), "scale": nums(&scale.to_array())}));
        spheres += 1;
    }
    assert_eq!(spheres, scene.occluders);

    // The camera: 30 m up, 75 m back from the centre, looking at a point 10 m behind it on the ground.
    let (eye, target) = (Vec3::new(0.0, 30.0, 75.0), Vec3::new(0.0, 0.0, 10.0));
    let camera = Transform::from_translation(eye).looking_to(target - eye, Vec3::Y);
    let mut cam_node = node_transform(&camera);
    cam_node["name"] = json!("camera");
    cam_node["camera"] = json!(0);
    nodes.push(cam_node);

    while !buffers.bin.len().is_multiple_of(4) {
        buffers.bin.push(0);
    }
    let doc = json!({
        "asset": {"version": "2.0", "generator": format!("kelvin examples/export_scaling_gltf.rs (spawn_scaling_scene, {n} lights, seed {seed})")},
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": lights}},
        "scene": 0,
        "scenes": [{"nodes": (0..nodes.len()).collect::<Vec<_>>()}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "cameras": [{"type": "perspective", "perspective": {"yfov": 50f32.to_radians(), "znear": 0.05}}],
        "accessors": buffers.accessors,
        "bufferViews": buffers.views,
        "buffers": [{"byteLength": buffers.bin.len()}],
    });
    let mut text = serde_json::to_vec(&doc).expect("JSON");
    while !text.len().is_multiple_of(4) {
        text.push(b' ');
    }
    let total = 12 + 8 + text.len() + 8 + buffers.bin.len();
    let mut glb = Vec::with_capacity(total);
    for word in [0x4654_6C67u32, 2, total as u32, text.len() as u32, 0x4E4F_534A] {
        glb.extend(word.to_le_bytes());
    }
    glb.extend(&text);
    for word in [buffers.bin.len() as u32, 0x004E_4942] {
        glb.extend(word.to_le_bytes());
    }
    glb.extend(&buffers.bin);
    if let Some(dir) = out.parent() {
        std::fs::create_dir_all(dir).expect("create the output folder");
    }
    std::fs::write(&out, &glb).unwrap_or_else(|e| panic!("cannot write {}: {e}", out.display()));
    println!(
        "wrote {} ({} bytes): {} lights, {} spheres, ground {:.0} m square",
        out.display(),
        glb.len(),
        scene.lights.len(),
        spheres,
        2.0 * scene.half_extent + 20.0
    );
}

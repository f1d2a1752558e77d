//! `kelvin bake lightmaps`: texels against closed forms (a quad under a point light, a spot and a
//! uniform sky; a closed white room, depth by depth), light through walls, KTX2 files read back
//! bit for bit, bad input, and Bevy's CornellBox end to end through the program.

mod common;

use std::path::Path;

use glam::Vec3;
use kelvin::bake::ktx2::{self, Format, Supercompression, Texture};
use kelvin::bake::{
    BakeError, BakeReport, BakedLight, Lightmap, LightmapOptions, TexelState, bake_lightmaps, write_lightmaps,
};
use kelvin::light::UniformInfiniteLight;
use kelvin::render::job::RenderJob;
use kelvin::render::path::PathDepth;
use kelvin::sampling::smooth_step;
use serde_json::{Value, json};

use common::files::{TempDir, test_data};

/// Luminance of linear sRGB (Rec. 709 weights, as kelvin's photometry).
fn lum(c: Vec3) -> f64 {
    kelvin::scene::image::LUMINANCE_WEIGHTS.dot(c) as f64
}

/// A triangle-list primitive: positions, TEXCOORD_1 (if any), indices, material index.
struct Prim {
    positions: Vec<[f32; 3]>,
    uv1: Option<Vec<[f32; 2]>>,
    indices: Vec<u32>,
    material: usize,
}

/// A horizontal quad at height `y` over [x0, x1] x [z0, z1], facing +Y, its uv1 the whole
/// [0, 1]^2 with u along +x and v along +z (so texel row 0 is at z0).
fn floor(x: [f32; 2], z: [f32; 2], y: f32, material: usize) -> Prim {
    let positions = vec![[x[0], y, z[0]], [x[1], y, z[0]], [x[1], y, z[1]], [x[0], y, z[1]]];
    let uv1 = Some(vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
    Prim { positions, uv1, indices: vec![0, 2, 1, 0, 3, 2], material }
}

/// A closed box from `lo` to `hi`, faces outward (or inward), each face a cell of a 3 x 2 uv1
/// atlas with gutters (`uv1`) or without uv1.
fn cuboid(lo: Vec3, hi: Vec3, inward: bool, uv1: bool, material: usize) -> Prim {
    let (mut positions, mut uvs, mut indices) = (Vec::new(), Vec::new(), Vec::new());
    for face in 0..6u32 {
        let (a, positive) = ((face / 2) as usize, face % 2 == 1);
        let (b, c) = ((a + 1) % 3, (a + 2) % 3);
        let base = positions.len() as u32;
        for (sb, sc) in [(false, false), (true, false), (true, true), (false, true)] {
            let mut p = Vec3::ZERO;
            p[a] = if positive { hi[a] } else { lo[a] };
            p[b] = if sb { hi[b] } else { lo[b] };
            p[c] = if sc { hi[c] } else { lo[c] };
            positions.push(p.to_array());
            let (cu, cv) = ((face % 3) as f32, (face / 3) as f32);
            let g = 0.15;
            uvs.push([(cu + if sb { 1.0 - g } else { g }) / 3.0, (cv + if sc { 1.0 - g } else { g }) / 2.0]);
        }
        // Corners 0, 1, 2 wind to +e_a (e_b x e_c = e_a).
        let front_is_plus = positive != inward;
        let order = if front_is_plus { [0, 1, 2, 0, 2, 3] } else { [0, 2, 1, 0, 3, 2] };
        indices.extend(order.map(|i| base + i));
    }
    Prim { positions, uv1: uv1.then_some(uvs), indices, material }
}

/// A glTF document built in memory: meshes (one node each), materials, punctual lights.
#[derive(Default)]
struct Doc {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
    meshes: Vec<Value>,
    nodes: Vec<Value>,
    materials: Vec<Value>,
    lights: Vec<Value>,
}

impl Doc {
    fn accessor(&mut self, bytes: Vec<u8>, count: usize, ty: &str, component: u32) -> usize {
        self.views.push(json!({ "buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len() }));
        self.bin.extend(bytes);
        let mut a = json!({ "bufferView": self.views.len() - 1, "componentType": component, "count": count, "type": ty });
        if ty == "VEC3" {
            let p: Vec<f32> = self.bin[self.bin.len() - count * 12..]
                .chunks(4)
                .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .collect();
            let axis = |k: usize, f: fn(f32, f32) -> f32| p.iter().skip(k).step_by(3).copied().reduce(f).unwrap();
            a["min"] = json!([axis(0, f32::min), axis(1, f32::min), axis(2, f32::min)]);
            a["max"] = json!([axis(0, f32::max), axis(1, f32::max), axis(2, f32::max)]);
        }
        self.accessors.push(a);
        self.accessors.len() - 1
    }

    /// A Lambertian material (no specular lobe) of albedo `rho`, emitting `nits` (front faces).
    fn material(&mut self, rho: f32, nits: f32) -> usize {
        self.materials.push(json!({
            "pbrMetallicRoughness": { "baseColorFactor": [rho, rho, rho, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0 },
            "emissiveFactor": if nits > 0.0 { [1.0, 1.0, 1.0] } else { [0.0, 0.0, 0.0] },
            "extensions": {
                "KHR_materials_specular": { "specularFactor": 0.0 },
                "KHR_materials_emissive_strength": { "emissiveStrength": nits.max(1.0) }
            }
        }));
        self.materials.len() - 1
    }

    /// A mesh named `name` of `prims`, placed at the origin by its own node.
    fn mesh(&mut self, name: &str, prims: &[Prim]) {
        let mut primitives = Vec::new();
        for p in prims {
            let floats = |v: &[[f32; 3]]| v.iter().flatten().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
            let position = self.accessor(floats(&p.positions), p.positions.len(), "VEC3", 5126);
            let index_bytes = p.indices.iter().flat_map(|i| i.to_le_bytes()).collect();
            let indices = self.accessor(index_bytes, p.indices.len(), "SCALAR", 5125);
            let mut attributes = json!({ "POSITION": position });
            if let Some(uv) = &p.uv1 {
                let bytes = uv.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
                attributes["TEXCOORD_1"] = json!(self.accessor(bytes, uv.len(), "VEC2", 5126));
            }
            primitives.push(json!({ "attributes": attributes, "indices": indices, "material": p.material }));
        }
        self.meshes.push(json!({ "name": name, "primitives": primitives }));
        self.nodes.push(json!({ "name": format!("{name}.node"), "mesh": self.meshes.len() - 1 }));
    }

    /// A KHR_lights_punctual light (`light` without its `type`-independent fields) at `at`,
    /// turned by the quaternion `rotation`.
    fn light(&mut self, light: Value, at: Vec3, rotation: [f32; 4]) {
        self.lights.push(light);
        let ext = json!({ "KHR_lights_punctual": { "light": self.lights.len() - 1 } });
        self.nodes.push(json!({ "translation": at.to_array(), "rotation": rotation, "extensions": ext }));
    }

    fn write(&self, path: &Path) {
        use base64::Engine;
        let uri = format!(
            "data:application/octet-stream;base64,{}",
            base64::engine::general_purpose::STANDARD.encode(&self.bin)
        );
        let mut doc = json!({
            "asset": { "version": "2.0" },
            "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_specular", "KHR_materials_emissive_strength"],
            "scene": 0,
            "scenes": [{ "nodes": (0..self.nodes.len()).collect::<Vec<_>>() }],
            "nodes": self.nodes,
            "meshes": self.meshes,
            "materials": self.materials,
            "buffers": [{ "uri": uri, "byteLength": self.bin.len() }],
            "bufferViews": self.views,
            "accessors": self.accessors,
        });
        if !self.lights.is_empty() {
            doc["extensions"] = json!({ "KHR_lights_punctual": { "lights": self.lights } });
        }
        std::fs::write(path, serde_json::to_vec(&doc).unwrap()).unwrap();
    }
}

/// Bakes `doc` (written into `dir`) with `opts`; `extra` may spawn more lights into the world.
fn bake(dir: &TempDir, doc: &Doc, opts: &LightmapOptions, extra: impl FnOnce(&mut bevy_ecs::world::World)) -> BakeReport {
    let path = dir.join("scene.gltf");
    doc.write(&path);
    let mut loaded = RenderJob { scene: Some(path), seed: 7, ..RenderJob::default() }.load().unwrap();
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    extra(&mut loaded.world);
    bake_lightmaps(&mut loaded, opts, |_| {}).unwrap()
}

/// Every baked texel's luminance against `expected(texel)` (None: not checked): within 4 sigma
/// each (sigma from the texel's own samples, plus `floor` relative for f32 and colour rounding),
/// 99% of them within 3 sigma, and their mean error within 3 sigma of the mean.
fn check_texels(map: &Lightmap, expected: impl Fn(usize) -> Option<f64>, floor: f64, what: &str) {
    let (mut n, mut within3, mut err_sum, mut var_sum, mut e_sum) = (0usize, 0usize, 0.0f64, 0.0f64, 0.0f64);
    for (i, (&t, &state)) in map.texels.iter().zip(&map.state).enumerate() {
        let Some(e) = expected(i).filter(|_| state == TexelState::Baked) else { continue };
        let (m, s) = (lum(t), lum(map.std_error[i]));
        let tol = floor * e.abs() + 1e-9;
        assert!((m - e).abs() <= 4.0 * s + tol, "{what}: texel {i}: {m} vs {e} (sigma {s})");
        within3 += ((m - e).abs() <= 3.0 * s + tol) as usize;
        (n, err_sum, var_sum, e_sum) = (n + 1, err_sum + (m - e), var_sum + s * s, e_sum + e);
    }
    assert!(n > 0, "{what}: no texel checked");
    assert!(within3 as f64 >= 0.99 * n as f64 - 1.0, "{what}: {within3} of {n} texels within 3 sigma");
    let (mean_err, sigma) = (err_sum / n as f64, var_sum.sqrt() / n as f64);
    eprintln!("{what}: {n} texels, mean error {mean_err:.3e} (sigma of the mean {sigma:.3e})");
    // f32 sums of many samples round at a few parts in 10^7.
    let rounding = 1e-5 * e_sum / n as f64;
    assert!(mean_err.abs() <= 3.0 * sigma + rounding, "{what}: mean error {mean_err} vs sigma {sigma}");
}

/// The mean over texel `i` of a `size` x `size` lightmap on the quad [-1, 1]^2 (y = 0) of `f(x, z)`,
/// by the midpoint rule on 12 x 12 points.
fn texel_mean(i: usize, size: usize, f: impl Fn(f64, f64) -> f64) -> f64 {
    let (tx, tz) = ((i % size) as f64, (i / size) as f64);
    let k = 12;
    let mut sum = 0.0;
    for a in 0..k {
        for b in 0..k {
            let x = -1.0 + 2.0 * (tx + (a as f64 + 0.5) / k as f64) / size as f64;
            let z = -1.0 + 2.0 * (tz + (b as f64 + 0.5) / k as f64) / size as f64;
            sum += f(x, z);
        }
    }
    sum / (k * k) as f64
}

const SIZE: usize = 16;

fn quad_doc() -> Doc {
    let mut doc = Doc::default();
    let m = doc.material(0.8, 0.0);
    doc.mesh("quad", &[floor([-1.0, 1.0], [-1.0, 1.0], 0.0, m)]);
    doc
}

fn quad_options() -> LightmapOptions {
    LightmapOptions { size: SIZE as u32, spp: 64, ..LightmapOptions::default() }
}

#[test]
fn a_point_light_gives_e_over_pi_at_every_texel() {
    let dir = TempDir::new("bake", "point");
    let mut doc = quad_doc();
    let (light, intensity) = (Vec3::new(0.3, 1.0, -0.2), 10.0);
    doc.light(json!({ "type": "point", "intensity": intensity }), light, [0.0, 0.0, 0.0, 1.0]);
    let report = bake(&dir, &doc, &quad_options(), |_| {});
    let map = &report.lightmaps[0];
    assert_eq!((report.lightmaps.len(), map.name.as_str(), map.size), (1, "quad", SIZE as u32));
    // E = I cos(theta) / d^2 = I h / d^3; the texel holds E / pi.
    let e = |x: f64, z: f64| {
        let d = Vec3::new(light.x - x as f32, light.y, light.z - z as f32).as_dvec3();
        intensity as f64 * d.y / d.length().powi(3) / std::f64::consts::PI
    };
    assert!(map.state.iter().all(|s| *s == TexelState::Baked));
    check_texels(map, |i| Some(texel_mean(i, SIZE, e)), 1e-3, "point light");
}

#[test]
fn a_spot_light_gives_e_over_pi_inside_and_nothing_outside_its_cone() {
    let dir = TempDir::new("bake", "spot");
    let mut doc = quad_doc();
    let (height, intensity, inner, outer) = (1.2f64, 20.0, 0.3f64, 0.6f64);
    let spot = json!({ "type": "spot", "intensity": intensity, "spot": { "innerConeAngle": inner, "outerConeAngle": outer } });
    // Aimed down: -Z turned onto -Y (a quarter turn about X).
    let half = std::f32::consts::FRAC_1_SQRT_2;
    doc.light(spot, Vec3::new(0.0, height as f32, 0.0), [-half, 0.0, 0.0, half]);
    let report = bake(&dir, &doc, &quad_options(), |_| {});
    let map = &report.lightmaps[0];
    let e = |x: f64, z: f64| {
        let d = (x * x + z * z + height * height).sqrt();
        let falloff = smooth_step((height / d) as f32, outer.cos() as f32, inner.cos() as f32) as f64;
        intensity * falloff * height / d.powi(3) / std::f64::consts::PI
    };
    // Texels across the cone's edge hold the light in a sliver that few samples find: their
    // spread says little about their error, so they are left out.
    let edge = height * outer.tan();
    let across_edge = |i: usize| {
        let side = 2.0 / SIZE as f64;
        let (x0, z0) = (-1.0 + side * (i % SIZE) as f64, -1.0 + side * (i / SIZE) as f64);
        let (x1, z1) = (x0 + side, z0 + side);
        let near = 0f64.clamp(x0, x1).hypot(0f64.clamp(z0, z1));
        let far = x0.abs().max(x1.abs()).hypot(z0.abs().max(z1.abs()));
        near < edge && far > edge
    };
    let crossing = (0..SIZE * SIZE).filter(|&i| across_edge(i)).count();
    assert!(crossing < SIZE * SIZE / 4, "{crossing}");
    check_texels(map, |i| (!across_edge(i)).then(|| texel_mean(i, SIZE, e)), 1e-3, "spot light");
    // The corners lie outside the outer cone (tan 0.6 * 1.2 = 0.82 < 1): nothing at all.
    for corner in [0, SIZE - 1, SIZE * (SIZE - 1), SIZE * SIZE - 1] {
        assert_eq!(map.texels[corner], Vec3::ZERO, "corner texel {corner}");
    }
}

#[test]
fn a_uniform_sky_gives_its_radiance_at_every_texel() {
    let dir = TempDir::new("bake", "sky");
    let nits = 250.0;
    let report = bake(&dir, &quad_doc(), &quad_options(), |world| {
        world.spawn((UniformInfiniteLight::nits(nits), kelvin::geometry::Transform::IDENTITY));
    });
    // E = pi L over the open hemisphere: E / pi = L.
    check_texels(&report.lightmaps[0], |_| Some(nits as f64), 1e-3, "uniform sky");
}

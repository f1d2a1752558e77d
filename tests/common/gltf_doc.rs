//! A glTF document built in memory, for tests that write scenes: triangle-list meshes (each placed
//! by its own node, with lightmap uvs or without), Lambertian materials that may emit, and
//! KHR_lights_punctual lights; buffers go into a base64 data URI.

use std::path::Path;

use glam::Vec3;
use serde_json::{Value, json};

/// A triangle-list primitive: positions, TEXCOORD_1 (if any), indices, material index.
pub struct Prim {
    pub positions: Vec<[f32; 3]>,
    pub uv1: Option<Vec<[f32; 2]>>,
    pub indices: Vec<u32>,
    pub material: usize,
}

/// A horizontal quad at height `y` over [x0, x1] x [z0, z1], facing +Y, its uv1 the whole
/// [0, 1]^2 with u along +x and v along +z (so texel row 0 is at z0).
pub fn floor(x: [f32; 2], z: [f32; 2], y: f32, material: usize) -> Prim {
    let positions = vec![[x[0], y, z[0]], [x[1], y, z[0]], [x[1], y, z[1]], [x[0], y, z[1]]];
    let uv1 = Some(vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
    Prim { positions, uv1, indices: vec![0, 2, 1, 0, 3, 2], material }
}

/// A closed box from `lo` to `hi`, faces outward (or inward), each face a cell of a 3 x 2 uv1
/// atlas with gutters (`uv1`) or without uv1.
pub fn cuboid(lo: Vec3, hi: Vec3, inward: bool, uv1: bool, material: usize) -> Prim {
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
pub struct Doc {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
    meshes: Vec<Value>,
    nodes: Vec<Value>,
    materials: Vec<Value>,
    lights: Vec<Value>,
    cameras: Vec<Value>,
    /// Nodes that are another node's child (not scene roots).
    children: Vec<usize>,
}

impl Doc {
    fn accessor(&mut self, bytes: Vec<u8>, count: usize, ty: &str, component: u32) -> usize {
        self.views.push(json!({ "buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len() }));
        self.bin.extend(bytes);
        let mut a =
            json!({ "bufferView": self.views.len() - 1, "componentType": component, "count": count, "type": ty });
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
    pub fn material(&mut self, rho: f32, nits: f32) -> usize {
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

    /// Makes material `m` double-sided (glTF `doubleSided`: its back shades, and emits, as its front).
    #[allow(dead_code)]
    pub fn double_sided(&mut self, m: usize) {
        self.materials[m]["doubleSided"] = json!(true);
    }

    /// A mesh named `name` of `prims`, placed at the origin by its own node.
    pub fn mesh(&mut self, name: &str, prims: &[Prim]) {
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
    /// turned by the quaternion `rotation`; returns its node.
    pub fn light(&mut self, light: Value, at: Vec3, rotation: [f32; 4]) -> usize {
        self.lights.push(light);
        let ext = json!({ "KHR_lights_punctual": { "light": self.lights.len() - 1 } });
        self.nodes.push(json!({ "translation": at.to_array(), "rotation": rotation, "extensions": ext }));
        self.nodes.len() - 1
    }

    /// A perspective camera of vertical field of view `yfov` (radians) at `at`, turned by the
    /// quaternion `rotation`; returns its node.
    #[allow(dead_code)]
    pub fn camera(&mut self, yfov: f32, at: Vec3, rotation: [f32; 4]) -> usize {
        self.cameras.push(json!({ "type": "perspective", "perspective": { "yfov": yfov, "znear": 0.01 } }));
        let camera = self.cameras.len() - 1;
        self.nodes.push(json!({ "translation": at.to_array(), "rotation": rotation, "camera": camera }));
        self.nodes.len() - 1
    }

    /// A new node with the world matrix `matrix` whose child is node `child`; returns it.
    #[allow(dead_code)]
    pub fn parent(&mut self, child: usize, matrix: glam::Affine3A) -> usize {
        let m = glam::Mat4::from(matrix).to_cols_array();
        self.nodes.push(json!({ "matrix": m, "children": [child] }));
        self.children.push(child);
        self.nodes.len() - 1
    }

    pub fn write(&self, path: &Path) {
        use base64::Engine;
        let uri = format!(
            "data:application/octet-stream;base64,{}",
            base64::engine::general_purpose::STANDARD.encode(&self.bin)
        );
        let mut doc = json!({
            "asset": { "version": "2.0" },
            "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_specular", "KHR_materials_emissive_strength"],
            "scene": 0,
            "scenes": [{ "nodes": (0..self.nodes.len()).filter(|n| !self.children.contains(n)).collect::<Vec<_>>() }],
            "nodes": self.nodes,
        });
        // glTF allows no empty arrays: a scene of lights alone has no meshes, buffers or accessors.
        if !self.meshes.is_empty() {
            doc["meshes"] = json!(self.meshes);
            doc["materials"] = json!(self.materials);
            doc["buffers"] = json!([{ "uri": uri, "byteLength": self.bin.len() }]);
            doc["bufferViews"] = json!(self.views);
            doc["accessors"] = json!(self.accessors);
        }
        if !self.cameras.is_empty() {
            doc["cameras"] = json!(self.cameras);
        }
        if !self.lights.is_empty() {
            doc["extensions"] = json!({ "KHR_lights_punctual": { "lights": self.lights } });
        }
        std::fs::write(path, serde_json::to_vec(&doc).unwrap()).unwrap();
    }
}

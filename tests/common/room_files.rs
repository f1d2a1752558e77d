//! A small room whose scene file references other files, as production scenes do: its geometry in
//! `box.bin`, a texture `tex.png`, an IES profile `lamp.ies`, plus an environment map `env.hdr`
//! beside it. For the tests of what an output records about the files it was made from.

use std::path::{Path, PathBuf};

use glam::Vec3;
use serde_json::json;

/// The files [`write`] makes, by name.
pub const FILES: [&str; 4] = ["box.bin", "tex.png", "lamp.ies", "env.hdr"];

/// Floor (y = 0, facing up, uvs 0 and 1) and a lamp quad at `lamp_y` facing down, as glTF buffer bytes.
pub fn buffer(lamp_y: f32) -> Vec<u8> {
    let floor = [[-2.0, 0.0, -2.0], [-2.0, 0.0, 2.0], [2.0, 0.0, 2.0], [2.0, 0.0, -2.0]];
    let lamp = [[-0.5, lamp_y, -0.5], [0.5, lamp_y, -0.5], [0.5, lamp_y, 0.5], [-0.5, lamp_y, 0.5]];
    let uv = [[0.0f32, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, 0.0]];
    let mut bytes: Vec<u8> = floor.iter().flatten().flat_map(|x: &f32| x.to_le_bytes()).collect();
    bytes.extend(uv.iter().flatten().flat_map(|x| x.to_le_bytes()));
    bytes.extend(lamp.iter().flatten().flat_map(|x: &f32| x.to_le_bytes()));
    bytes.extend([0u16, 1, 2, 0, 2, 3].iter().flat_map(|i| i.to_le_bytes()));
    bytes
}

/// A 2x2 texture of grey `level`.
pub fn texture(path: &Path, level: f32) {
    kelvin::render::film_io::write_png(path, 2, 2, &[Vec3::splat(level); 4], 0.0).unwrap();
}

/// An 8x4 environment map of radiance `level`.
pub fn env_map(path: &Path, level: f32) {
    kelvin::render::film_io::write_hdr(path, 8, 4, &[Vec3::splat(level); 32]).unwrap();
}

/// Writes `room.gltf` and the files it references (and `env.hdr`) into `dir`; returns the scene's path.
pub fn write(dir: &Path) -> PathBuf {
    let bin = buffer(2.0);
    std::fs::write(dir.join("box.bin"), &bin).unwrap();
    texture(&dir.join("tex.png"), 0.5);
    env_map(&dir.join("env.hdr"), 0.2);
    std::fs::copy(super::files::test_data("ies/luxcore/ASA_15M_R2.ies"), dir.join("lamp.ies")).unwrap();
    let view = |offset: usize, length: usize| json!({ "buffer": 0, "byteOffset": offset, "byteLength": length });
    let vec3 = |view: usize, y: f32, half: f32| {
        json!({ "bufferView": view, "componentType": 5126, "count": 4, "type": "VEC3",
                "min": [-half, y, -half], "max": [half, y, half] })
    };
    let down = [-std::f32::consts::FRAC_1_SQRT_2, 0.0, 0.0, std::f32::consts::FRAC_1_SQRT_2];
    let doc = json!({
        "asset": { "version": "2.0" },
        "extensionsUsed": ["EXT_lights_ies", "KHR_materials_emissive_strength"],
        "scene": 0,
        "scenes": [{ "nodes": [0, 1, 2] }],
        "nodes": [
            { "name": "floor", "mesh": 0 },
            { "name": "lamp", "mesh": 1 },
            { "name": "spot", "translation": [1.0, 1.5, 0.0], "rotation": down,
              "extensions": { "EXT_lights_ies": { "light": 0, "multiplier": 1.0 } } }
        ],
        "meshes": [
            { "name": "floor", "primitives": [{ "attributes": { "POSITION": 0, "TEXCOORD_0": 1, "TEXCOORD_1": 1 },
                                                "indices": 3, "material": 0 }] },
            { "name": "lamp", "primitives": [{ "attributes": { "POSITION": 2 }, "indices": 3, "material": 1 }] }
        ],
        "materials": [
            { "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 }, "metallicFactor": 0.0 } },
            { "emissiveFactor": [1.0, 1.0, 1.0],
              "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": 50.0 } } }
        ],
        "textures": [{ "source": 0 }],
        "images": [{ "uri": "tex.png" }],
        "accessors": [
            vec3(0, 0.0, 2.0),
            { "bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2" },
            vec3(2, 2.0, 0.5),
            { "bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR" }
        ],
        "bufferViews": [view(0, 48), view(48, 32), view(80, 48), view(128, 12)],
        "buffers": [{ "uri": "box.bin", "byteLength": bin.len() }],
        "extensions": { "EXT_lights_ies": { "lights": [{ "uri": "lamp.ies" }] } }
    });
    let scene = dir.join("room.gltf");
    std::fs::write(&scene, serde_json::to_vec_pretty(&doc).unwrap()).unwrap();
    scene
}

/// Changes the file `name` of [`write`]'s room to another valid one (the lamp lower, a darker
/// texture or sky, a profile with a comment more).
pub fn change(dir: &Path, name: &str) {
    let path = dir.join(name);
    match name {
        "box.bin" => std::fs::write(&path, buffer(1.5)).unwrap(),
        "tex.png" => texture(&path, 0.25),
        "env.hdr" => env_map(&path, 0.1),
        "lamp.ies" => {
            let text = std::fs::read_to_string(&path).unwrap();
            std::fs::write(&path, text.replacen("\n", "\n[OTHER] changed\n", 1)).unwrap();
        }
        _ => panic!("{name} is not a file of the room"),
    }
}

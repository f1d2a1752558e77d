//! Writes small synthetic seed files for the fuzz corpora (run by `fuzz/seed.sh`; the real files from
//! tests/data are copied by the script itself):
//! - `env_map`: tiny EXR files in every compression the `exr` crate writes, f16 / f32 / u32, tiled, layered and
//!   grey; tiny Radiance HDR files (flat and run-length encoded).
//! - `ies_parse`: LM-63 files of every version, photometric type and symmetry, with TILT=INCLUDE.
//! - `gltf_import`: `.glb` files with an emissive textured triangle, every punctual light kind, an EXT_lights_ies
//!   light whose profile is in the binary chunk, a camera, sparse accessors and a triangle strip.
//!
//! With the test data folder as second argument, `renderling/shadow_mapping_sanity.gltf` and its `.bin` are also
//! packed into one `.glb` (the fuzz target loads from memory, where external buffers cannot be resolved).
//!
//! - `tile_exr`: tiles as `kelvin render --crop` writes them (with provenance), a whole image, a tile of an image
//!   from elsewhere (no provenance).
//! - `bake_part`: part files of a lightmap and a volume bake of a small scene.
//!
//! Usage: `cargo run --example make_seeds -- <corpus dir> [<data dir>]` (writes `<dir>/<target>/`).

use std::path::{Path, PathBuf};

use exr::prelude::{
    AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer, LayerAttributes, SmallVec, SpecificChannels,
    WritableImage, f16,
};
use glam::Vec3;
use kelvin::render::film_io::{write_hdr, write_png};
use serde_json::json;

fn main() {
    let root = PathBuf::from(std::env::args().nth(1).expect("usage: make_seeds <corpus dir>"));
    let targets = [
        ("env_map", env_seeds as fn(&Path)),
        ("ies_parse", ies_seeds),
        ("gltf_import", gltf_seeds),
        ("tile_exr", tile_seeds),
        ("bake_part", bake_part_seeds),
    ];
    for (name, write) in targets {
        let dir = root.join(name);
        std::fs::create_dir_all(&dir).expect("create corpus dir");
        write(&dir);
    }
    if let Some(data) = std::env::args().nth(2) {
        pack_external_gltf(&Path::new(&data).join("gltf/renderling/shadow_mapping_sanity.gltf"), &root);
    }
}

fn tile_seeds(dir: &Path) {
    use kelvin::provenance::Provenance;
    use kelvin::render::film_io::{write_exr_tile, write_exr_with};
    use kelvin::render::tiles::Crop;
    let (w, h) = (6u32, 5u32);
    let rgb = |c: Crop| (c.y0..c.y1).flat_map(|y| (c.x0..c.x1).map(move |x| pixel(x as usize, y as usize))).collect::<Vec<_>>();
    let made = Provenance::of_program().with("settings", "seed").with("scene", "sha256:00");
    for (k, crop) in [Crop { x0: 0, y0: 0, x1: 3, y1: 5 }, Crop { x0: 3, y0: 2, x1: 6, y1: 5 }].into_iter().enumerate() {
        let p = made.clone().with("tile", crop.to_string());
        write_exr_tile(&dir.join(format!("tile{k}.exr")), crop, w, h, &rgb(crop), &p).expect("write tile");
    }
    let whole = Crop { x0: 0, y0: 0, x1: w, y1: h };
    write_exr_with(&dir.join("whole.exr"), w as usize, h as usize, &rgb(whole), &made).expect("write image");
    write_exr_with(&dir.join("no_provenance.exr"), 2, 2, &[Vec3::ONE; 4], &Provenance::default()).expect("write");
}

fn bake_part_seeds(dir: &Path) {
    use kelvin::bake::{LightmapOptions, Part, VolumeOptions, bake_lightmaps_part, bake_volume_part};
    use kelvin::render::job::RenderJob;
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/gltf/bevy/CornellBox.glb");
    let job = RenderJob { scene: Some(scene), ..RenderJob::default() };
    let Ok(mut loaded) = job.load() else { return };
    let opts = LightmapOptions { size: 4, spp: 1, ..LightmapOptions::default() };
    for index in 0..2 {
        let part = bake_lightmaps_part(&mut loaded, &opts, Part { index, count: 2 }, |_| {}).expect("bake part");
        std::fs::write(dir.join(format!("lightmaps{index}.kbake")), part.to_bytes()).expect("write part");
    }
    let opts = VolumeOptions { resolution: glam::UVec3::new(2, 1, 1), spp: 1, ..VolumeOptions::default() };
    let part = bake_volume_part(&mut loaded, &opts, Part { index: 0, count: 3 }, |_| {}).expect("bake part");
    std::fs::write(dir.join("volume.kbake"), part.to_bytes()).expect("write part");
}

/// A `.gltf` whose single buffer is an external `.bin`, repacked as `.glb`.
fn pack_external_gltf(path: &Path, root: &Path) {
    let (Ok(text), Some(dir)) = (std::fs::read(path), path.parent()) else { return };
    let mut json: serde_json::Value = serde_json::from_slice(&text).expect("glTF JSON");
    let Some(uri) = json["buffers"][0]["uri"].as_str() else { return };
    let bin = std::fs::read(dir.join(uri)).expect("read .bin");
    json["buffers"][0].as_object_mut().expect("buffer object").remove("uri");
    let name = path.with_extension("glb").file_name().expect("file name").to_string_lossy().into_owned();
    std::fs::write(root.join("gltf_import").join(format!("packed_{name}")), glb(&json, &bin)).expect("write glb");
}

fn pixel(x: usize, y: usize) -> Vec3 {
    Vec3::new(x as f32 * 0.25, y as f32 * 0.5 + 0.1, 1.5 + (x * y) as f32)
}

fn env_seeds(dir: &Path) {
    let (w, h) = (8, 4);
    let encodings = [
        ("uncompressed", Encoding::UNCOMPRESSED),
        ("rle", Encoding::FAST_LOSSLESS),
        ("zip", Encoding::SMALL_LOSSLESS),
        ("piz", Encoding { compression: exr::compression::Compression::PIZ, ..Encoding::SMALL_LOSSLESS }),
        ("zip1", Encoding { compression: exr::compression::Compression::ZIP1, ..Encoding::SMALL_LOSSLESS }),
        ("pxr24", Encoding { compression: exr::compression::Compression::PXR24, ..Encoding::SMALL_LOSSLESS }),
        ("b44", Encoding { compression: exr::compression::Compression::B44, ..Encoding::SMALL_LOSSLESS }),
    ];
    for (name, encoding) in encodings {
        let f32s = SpecificChannels::rgb(|exr::math::Vec2(x, y): exr::math::Vec2<usize>| {
            let p = pixel(x, y);
            (p.x, p.y, p.z)
        });
        let image = Image::from_encoded_channels((w, h), encoding.clone(), f32s);
        image.write().to_file(dir.join(format!("f32_{name}.exr"))).expect("write exr");
        let halves = SpecificChannels::rgb(|exr::math::Vec2(x, y): exr::math::Vec2<usize>| {
            let p = pixel(x, y);
            (f16::from_f32(p.x), f16::from_f32(p.y), f16::from_f32(p.z))
        });
        let image = Image::from_encoded_channels((w, h), encoding, halves);
        image.write().to_file(dir.join(format!("f16_{name}.exr"))).expect("write exr");
    }
    // Tiled (2 x 2 tiles of 4 x 4 per level), u32 grey, and a layered file with a prefixed RGB next to depth.
    let tiled = Encoding { blocks: exr::prelude::Blocks::Tiles(exr::math::Vec2(4, 4)), ..Encoding::FAST_LOSSLESS };
    let channels = SpecificChannels::rgb(|exr::math::Vec2(x, y): exr::math::Vec2<usize>| {
        let p = pixel(x, y);
        (p.x, p.y, p.z)
    });
    Image::from_encoded_channels((w, h), tiled, channels).write().to_file(dir.join("tiled.exr")).expect("write exr");
    let list: SmallVec<[AnyChannel<FlatSamples>; 4]> =
        SmallVec::from_vec(vec![AnyChannel::new("Y", FlatSamples::U32((0..(w * h) as u32).collect()))]);
    Image::from_channels((w, h), AnyChannels::sort(list)).write().to_file(dir.join("grey_u32.exr")).expect("write");
    let plane = |f: fn(Vec3) -> f32| FlatSamples::F32((0..w * h).map(|i| f(pixel(i % w, i / w))).collect());
    let list: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::from_vec(vec![
        AnyChannel::new("depth.Z", plane(|_| 9.0)),
        AnyChannel::new("diffuse.R", plane(|v| v.x)),
        AnyChannel::new("diffuse.G", plane(|v| v.y)),
        AnyChannel::new("diffuse.B", plane(|v| v.z)),
    ]);
    let layer = Layer::new((w, h), LayerAttributes::default(), Encoding::SMALL_LOSSLESS, AnyChannels::sort(list));
    Image::from_layer(layer).write().to_file(dir.join("layered.exr")).expect("write exr");
    // Radiance HDR: 4 x 2 is written flat, 16 x 8 run-length encoded.
    for (w, h) in [(4, 2), (16, 8)] {
        let rgb: Vec<Vec3> = (0..w * h).map(|i| pixel(i % w, i / w)).collect();
        write_hdr(&dir.join(format!("rgbe_{w}x{h}.hdr")), w, h, &rgb).expect("write hdr");
    }
}

/// An LM-63 file: version line, keywords, tilt section, then the numbers.
fn ies_text(version: &str, tilt: &str, kind: u8, v: &[f64], h: &[f64], cd: impl Fn(f64, f64) -> f64) -> String {
    let join = |xs: &[f64]| xs.iter().map(|x| x.to_string()).collect::<Vec<_>>().join(" ");
    let mut s = format!("{version}[TEST] seed\n[MANUFAC] kelvin\n[MORE] fuzz\n{tilt}\n");
    s += &format!("1 -1 1 {} {} {kind} 2 0.5 0.6 0.1\n1.0 1.0 100\n", v.len(), h.len());
    s += &format!("{}\n{}\n", join(v), join(h));
    for &hh in h {
        s += &join(&v.iter().map(|&vv| cd(vv, hh)).collect::<Vec<_>>());
        s += "\n";
    }
    s
}

fn ies_seeds(dir: &Path) {
    let v_c = [0.0, 22.5, 45.0, 67.5, 90.0, 135.0, 180.0];
    let cd = |v: f64, h: f64| 100.0 + 50.0 * (v.to_radians().cos() + (h / 90.0).sin());
    let seeds = [
        ("c_rotational_2002.ies", ies_text("IESNA:LM-63-2002\n", "TILT=NONE", 1, &v_c, &[0.0], cd)),
        ("c_quadrant_1995.ies", ies_text("IESNA:LM-63-1995\n", "TILT=NONE", 1, &v_c, &[0.0, 45.0, 90.0], cd)),
        ("c_bilateral_2019.ies", ies_text("IES:LM-63-2019\n", "TILT=NONE", 1, &v_c, &[0.0, 90.0, 180.0], cd)),
        ("c_bilateral_90_270.ies", ies_text("IESNA91\n", "TILT=NONE", 1, &v_c, &[90.0, 180.0, 270.0], cd)),
        ("c_full_1986.ies", ies_text("", "TILT=NONE", 1, &v_c, &[0.0, 90.0, 180.0, 270.0, 360.0], cd)),
        ("b_lateral.ies", ies_text("IESNA:LM-63-2002\n", "TILT=NONE", 2, &[-90.0, 0.0, 90.0], &[0.0, 45.0, 90.0], cd)),
        ("a_full.ies", ies_text("IESNA:LM-63-2002\n", "TILT=NONE", 3, &[-90.0, 0.0, 90.0], &[-90.0, 0.0, 90.0], cd)),
        (
            "tilt_include.ies",
            ies_text("IESNA:LM-63-2002\n", "TILT=INCLUDE\n1\n3\n0 45 90\n1 0.9 0.7", 1, &v_c, &[0.0], cd),
        ),
        ("tilt_file.ies", ies_text("IESNA:LM-63-1995\n", "TILT=lamp.tlt", 1, &v_c, &[0.0], cd)),
    ];
    for (name, text) in seeds {
        std::fs::write(dir.join(name), text).expect("write ies");
    }
}

/// A binary glTF: 12-byte header, JSON chunk (space-padded), BIN chunk (zero-padded).
fn glb(json: &serde_json::Value, bin: &[u8]) -> Vec<u8> {
    let mut j = serde_json::to_vec(json).expect("json");
    j.resize(j.len().next_multiple_of(4), b' ');
    let mut b = bin.to_vec();
    b.resize(b.len().next_multiple_of(4), 0);
    let total = 12 + 8 + j.len() + 8 + b.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(j.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&j);
    out.extend_from_slice(&(b.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&b);
    out
}

/// Appends `bytes` to `bin` at a 4-byte boundary; returns (offset, length).
fn push(bin: &mut Vec<u8>, bytes: &[u8]) -> (usize, usize) {
    bin.resize(bin.len().next_multiple_of(4), 0);
    let at = bin.len();
    bin.extend_from_slice(bytes);
    (at, bytes.len())
}

fn f32_bytes(xs: &[f32]) -> Vec<u8> {
    xs.iter().flat_map(|x| x.to_le_bytes()).collect()
}

fn gltf_seeds(dir: &Path) {
    let mut bin = Vec::new();
    let positions = f32_bytes(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0]);
    let normals = f32_bytes(&[0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0]);
    let uvs = f32_bytes(&[0.0, 1.0, 1.0, 1.0, 0.0, 0.0, 1.0, 0.0]);
    let indices: Vec<u8> = [0u16, 1, 2, 2, 1, 3].iter().flat_map(|i| i.to_le_bytes()).collect();
    let sparse_idx: Vec<u8> = [1u8, 3].to_vec();
    let sparse_val = f32_bytes(&[2.0, 0.0, 0.0, 2.0, 2.0, 0.5]);
    let ies = ies_text("IESNA:LM-63-2002\n", "TILT=NONE", 1, &[0.0, 45.0, 90.0], &[0.0], |v, _| 200.0 - v);
    let png_path = std::env::temp_dir().join(format!("kelvin-make-seeds-{}.png", std::process::id()));
    write_png(&png_path, 2, 2, &[Vec3::X, Vec3::Y, Vec3::Z, Vec3::ONE], 0.0).expect("write png");
    let png = std::fs::read(&png_path).expect("read png");
    let _ = std::fs::remove_file(&png_path);

    let views: Vec<(usize, usize)> =
        [&positions[..], &normals, &uvs, &indices, &sparse_idx, &sparse_val, &png, ies.as_bytes()]
            .into_iter()
            .map(|b| push(&mut bin, b))
            .collect();
    let view = |i: usize| json!({ "buffer": 0, "byteOffset": views[i].0, "byteLength": views[i].1 });
    let full = json!({
        "asset": { "version": "2.0" },
        "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_emissive_strength", "EXT_lights_ies"],
        "scene": 0,
        "scenes": [{ "nodes": [0, 1, 2, 3, 4, 5, 6] }],
        "nodes": [
            { "mesh": 0, "translation": [0.0, 0.0, -2.0], "children": [7] },
            { "extensions": { "KHR_lights_punctual": { "light": 0 } }, "translation": [0.0, 3.0, 0.0] },
            { "extensions": { "KHR_lights_punctual": { "light": 1 } }, "rotation": [-0.7071068, 0.0, 0.0, 0.7071068] },
            { "extensions": { "KHR_lights_punctual": { "light": 2 } }, "scale": [1.0, 2.0, 1.0] },
            { "extensions": { "EXT_lights_ies": { "light": 0, "multiplier": 2.0, "color": [1.0, 0.8, 0.6] } } },
            { "camera": 0, "matrix": [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 5.0, 1.0] },
            { "mesh": 1 },
            { "mesh": 0, "translation": [3.0, 0.0, 0.0] }
        ],
        "meshes": [
            { "primitives": [{
                "attributes": { "POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2 }, "indices": 3, "material": 0
            }] },
            { "primitives": [{ "attributes": { "POSITION": 4 }, "mode": 5, "material": 1 }] }
        ],
        "materials": [
            {
                "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 }, "metallicFactor": 0.0 },
                "emissiveFactor": [1.0, 0.5, 0.25],
                "emissiveTexture": { "index": 0 },
                "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": 4.0 } },
                "doubleSided": true
            },
            { "pbrMetallicRoughness": { "baseColorFactor": [0.5, 0.5, 0.5, 1.0], "roughnessFactor": 0.3 } }
        ],
        "textures": [{ "source": 0 }],
        "images": [{ "bufferView": 6, "mimeType": "image/png" }],
        "cameras": [{ "type": "perspective", "perspective": { "yfov": 0.8, "znear": 0.1, "aspectRatio": 1.5 } }],
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
              "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0] },
            { "bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3" },
            { "bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2" },
            { "bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR" },
            { "bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
              "sparse": { "count": 2, "indices": { "bufferView": 4, "componentType": 5121 },
                          "values": { "bufferView": 5 } } }
        ],
        "bufferViews": [view(0), view(1), view(2), view(3), view(4), view(5), view(6), view(7)],
        "buffers": [{ "byteLength": bin.len() }],
        "extensions": {
            "KHR_lights_punctual": { "lights": [
                { "type": "point", "intensity": 50.0, "color": [1.0, 0.9, 0.8], "range": 10.0 },
                { "type": "spot", "intensity": 80.0, "spot": { "innerConeAngle": 0.2, "outerConeAngle": 0.6 } },
                { "type": "directional", "intensity": 3.0 }
            ] },
            "EXT_lights_ies": { "lights": [{ "bufferView": 7, "mimeType": "application/x-ies-lm-63" }] }
        }
    });
    std::fs::write(dir.join("synthetic_full.glb"), glb(&full, &bin)).expect("write glb");
    // The same document as .gltf JSON with the buffer as a data: URI.
    let mut as_json = full.clone();
    use base64::Engine;
    let b64 = base64::engine::general_purpose::STANDARD.encode(&bin);
    as_json["buffers"][0]["uri"] = json!(format!("data:application/octet-stream;base64,{b64}"));
    std::fs::write(dir.join("synthetic_full.gltf"), serde_json::to_vec(&as_json).expect("json")).expect("write");
    // Quantised positions (KHR_mesh_quantization style: normalised u8) and a triangle fan, no material.
    let mut bin = Vec::new();
    push(&mut bin, &[0, 0, 0, 0, 255, 0, 0, 0, 0, 255, 0, 0, 255, 255, 0, 0]);
    let quantised = json!({
        "asset": { "version": "2.0" },
        "extensionsUsed": ["KHR_mesh_quantization"],
        "nodes": [{ "mesh": 0 }],
        "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0 }, "mode": 6 }] }],
        "accessors": [{ "bufferView": 0, "componentType": 5121, "normalized": true, "count": 4, "type": "VEC3" }],
        "bufferViews": [{ "buffer": 0, "byteLength": 16, "byteStride": 4 }],
        "buffers": [{ "byteLength": 16 }]
    });
    std::fs::write(dir.join("quantised_fan.glb"), glb(&quantised, &bin)).expect("write glb");
}

//! glTF import: the real scenes in tests/data/gltf (counts, emissive strengths, light kinds, external buffers
//! and textures), the Khronos glTF-Validator's valid and invalid files against their reports, and broken files
//! made here (truncated .glb, short or missing buffer, missing or garbage textures, out-of-bounds accessors).

use std::path::{Path, PathBuf};

use bevy_ecs::prelude::*;
use glam::{Vec3, Vec4};
use kelvin::geometry::{Mesh, Transform};
use kelvin::light::{AreaLight, GoniometricLight};
use kelvin::rng::SplitMix64;
use kelvin::scene::gltf::{GltfError, GltfScene, IesSource, LightKind, load_gltf, load_gltf_from_bytes};
use kelvin::scene::ies::IesProfile;
use kelvin::scene::spawn::{SpawnReport, spawn_gltf};
use kelvin::shading::{DirectLighting, LightSelection, Settings, ShadingBatch};
use kelvin::systems::LightingPlugin;
use serde_json::{Value, json};

mod common;
use common::files::{TempDir, test_data};

fn temp_dir(test: &str) -> TempDir {
    TempDir::new("gltf", test)
}

fn gltf_dir() -> PathBuf {
    test_data("gltf")
}

/// Every .gltf / .glb under `dir`, sorted.
fn gltf_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).expect("read dir").flatten() {
            let p = entry.path();
            if p.is_dir() {
                stack.push(p);
            } else if matches!(p.extension().and_then(|e| e.to_str()), Some("gltf" | "glb")) {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

fn load_ok(path: &Path) -> GltfScene {
    load_gltf(path).unwrap_or_else(|e| panic!("{} failed to load: {e}", path.display()))
}

fn triangle_count(scene: &GltfScene) -> usize {
    scene.instances.iter().flat_map(|i| &scene.meshes[i.mesh].primitives).map(|p| p.indices.len() / 3).sum()
}

#[test]
fn every_sample_scene_loads() {
    let dir = gltf_dir();
    let files: Vec<PathBuf> =
        gltf_files(&dir).into_iter().filter(|p| !p.to_string_lossy().contains("khronos-validator")).collect();
    assert!(files.len() >= 14, "expected the sample scenes, found {}", files.len());
    for path in files {
        let scene = load_ok(&path);
        println!(
            "{}: {} meshes, {} instances, {} triangles, {} materials, {} textures, {} lights, {} cameras, {} warnings",
            path.strip_prefix(&dir).unwrap().display(),
            scene.meshes.len(),
            scene.instances.len(),
            triangle_count(&scene),
            scene.materials.len(),
            scene.textures.len(),
            scene.lights.len(),
            scene.cameras.len(),
            scene.warnings.len()
        );
        for w in &scene.warnings {
            println!("    warning: {w}");
        }
        assert!(!scene.instances.is_empty() || !scene.lights.is_empty(), "{}: nothing placed", path.display());
        for mesh in &scene.meshes {
            for p in &mesh.primitives {
                assert!(!p.indices.is_empty() && p.indices.len() % 3 == 0);
                assert!(p.indices.iter().all(|&i| (i as usize) < p.positions.len()));
                assert!(p.positions.iter().all(|v| v.is_finite()));
                assert!(p.material.is_none_or(|m| m < scene.materials.len()));
            }
        }
        for m in &scene.materials {
            for t in [m.base_color_texture, m.metallic_roughness_texture, m.emissive_texture].into_iter().flatten() {
                assert!(t < scene.textures.len());
            }
        }
    }
}

#[test]
fn cornell_box_has_an_emitter_of_strength_100() {
    let dir = gltf_dir();
    let scene = load_ok(&dir.join("bevy/CornellBox.glb"));
    assert_eq!((scene.meshes.len(), scene.instances.len(), scene.materials.len()), (4, 4, 5));
    let emitters: Vec<_> = scene.materials.iter().filter(|m| m.emissive != Vec3::ZERO).collect();
    assert_eq!(emitters.len(), 1);
    assert_eq!(emitters[0].name.as_deref(), Some("Emitter_Light_temp"));
    assert_eq!(emitters[0].emissive_strength, 100.0);
    assert_eq!(emitters[0].emissive, Vec3::splat(100.0));
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
}

#[test]
fn emissive_strength_test_has_strengths_1_to_16() {
    let dir = gltf_dir();
    let scene = load_ok(&dir.join("renderling/EmissiveStrengthTest.glb"));
    let factor = Vec3::new(0.1, 0.5, 0.9);
    for (name, strength) in [("Emit1", 1.0), ("Emit2", 2.0), ("Emit4", 4.0), ("Emit8", 8.0), ("Emit16", 16.0)] {
        let m = scene.materials.iter().find(|m| m.name.as_deref() == Some(name)).expect(name);
        assert_eq!(m.emissive_strength, strength, "{name}");
        assert!((m.emissive - factor * strength).abs().max_element() < 1e-5, "{name}: {}", m.emissive);
    }
    // SOURCES.md: 60 emissive triangles.
    let emissive_triangles: usize = scene
        .instances
        .iter()
        .flat_map(|i| &scene.meshes[i.mesh].primitives)
        .filter(|p| p.material.is_some_and(|m| scene.materials[m].emissive != Vec3::ZERO))
        .map(|p| p.indices.len() / 3)
        .sum();
    assert_eq!(emissive_triangles, 60);
}

#[test]
fn renderling_lights_have_the_stated_kinds() {
    let dir = gltf_dir();
    let kinds = |file: &str| -> Vec<LightKind> {
        load_ok(&dir.join("renderling").join(file)).lights.iter().map(|l| l.kind).collect()
    };
    let is_spot = |k: &LightKind| matches!(k, LightKind::Spot { .. });
    assert!(matches!(kinds("spot_one.glb").as_slice(), [k] if is_spot(k)));
    assert_eq!(kinds("spot_lights.glb").iter().filter(|k| is_spot(k)).count(), 2);
    assert_eq!(kinds("four_spotlights.glb").iter().filter(|k| is_spot(k)).count(), 4);
    assert_eq!(kinds("shadow_mapping_spots.glb").iter().filter(|k| is_spot(k)).count(), 2);
    assert_eq!(kinds("shadow_mapping_point.glb"), vec![LightKind::Point]);
    assert_eq!(kinds("shadow_mapping_points.glb"), vec![LightKind::Point; 4]);
    for file in ["shadow_mapping_sanity.gltf", "cheetah_cone.glb", "light_tiling_test.glb"] {
        assert_eq!(kinds(file), vec![LightKind::Directional], "{file}");
    }

    let spot = load_ok(&dir.join("renderling/spot_one.glb"));
    let light = &spot.lights[0];
    assert!((light.intensity - 54351.41).abs() < 0.1, "cd: {}", light.intensity);
    let LightKind::Spot { inner_cone_angle, outer_cone_angle } = light.kind else { unreachable!() };
    assert!((inner_cone_angle - 0.2713987).abs() < 1e-6 && (outer_cone_angle - 0.5427974).abs() < 1e-6);
    assert!(spot.warnings.is_empty(), "{:?}", spot.warnings);
    // Perspective camera from the file; the orthographic one of cheetah_cone is skipped with a warning.
    assert!((spot.cameras[0].yfov - 0.3995965).abs() < 1e-6 && spot.cameras[0].aspect == Some(1.7777778));
    let cheetah = load_ok(&dir.join("renderling/cheetah_cone.glb"));
    assert!(cheetah.cameras.is_empty() && cheetah.warnings.iter().any(|w| w.contains("orthographic")));

    let tiling = load_ok(&dir.join("renderling/light_tiling_test.glb"));
    let base = tiling.materials.iter().find(|m| m.name.as_deref() == Some("base.020")).unwrap();
    assert_eq!((base.specular_factor, base.ior), (0.0, 1.45));
}

#[test]
fn mixed_lighting_example_loads_its_bin_and_jpeg_textures() {
    let dir = gltf_dir();
    let scene = load_ok(&dir.join("bevy/MixedLightingExample/MixedLightingExample.gltf"));
    assert_eq!(scene.meshes.len(), 6);
    assert!(triangle_count(&scene) > 1000);
    let textured = scene.materials.iter().filter(|m| m.base_color_texture.is_some()).count();
    assert!(textured >= 3, "{textured} materials with a base colour texture");
    assert!(scene.materials.iter().any(|m| m.metallic_roughness_texture.is_some()));
    assert!(scene.textures.len() >= 3 && scene.textures.iter().all(|t| t.width > 0 && t.height > 0));
    assert_eq!(scene.lights.len(), 1);
    assert_eq!((scene.lights[0].kind, scene.lights[0].intensity), (LightKind::Directional, 2049.0));
    // KHR_texture_transform is required by the file but not supported: a warning, not an error.
    assert!(scene.warnings.iter().any(|w| w.contains("/extensionsRequired") && w.contains("KHR_texture_transform")));
    assert!(!scene.warnings.iter().any(|w| w.contains("not found")), "{:?}", scene.warnings);
}

/// The JSON pointer of one of our warnings ("<file>: <pointer>: <message>").
fn warning_pointer<'a>(warning: &'a str, what: &str) -> &'a str {
    let rest = warning.strip_prefix(what).and_then(|r| r.strip_prefix(": ")).unwrap_or(warning);
    rest.split(": ").next().unwrap_or("")
}

/// Every error the Khronos glTF-Validator reports for its own test files (each `issues.messages[]` entry of
/// severity 0) is matched: either the file is rejected, or a warning of ours names that error's JSON pointer
/// exactly, one warning per error (two errors at one pointer need two warnings there). Files without errors load.
#[test]
fn validator_files_agree_with_their_reports() {
    let dir = gltf_dir();
    let files = gltf_files(&dir.join("khronos-validator"));
    assert!(files.len() >= 22, "expected the validator files, found {}", files.len());
    println!("{:<75} {:>6}  outcome", "file", "errors");
    let mut unmatched = Vec::new();
    for path in files {
        let report: Value =
            serde_json::from_slice(&std::fs::read(path.with_extension("gltf.report.json")).unwrap()).unwrap();
        let num_errors = report["issues"]["numErrors"].as_u64().unwrap();
        let errors: Vec<(&str, &str, &str)> = report["issues"]["messages"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|m| m["severity"] == 0)
            .map(|m| (m["code"].as_str().unwrap(), m["pointer"].as_str().unwrap(), m["message"].as_str().unwrap()))
            .collect();
        let name = path.strip_prefix(&dir).unwrap().display().to_string();
        assert_eq!(errors.len() as u64, num_errors, "{name}: numErrors differs from the error messages listed");
        let what = path.display().to_string();
        let result = load_gltf(&path);
        let outcome = match &result {
            Err(e) => format!("error: {e}"),
            Ok(s) if s.warnings.is_empty() => format!("ok, {} lights, no warnings", s.lights.len()),
            Ok(s) => {
                let w: Vec<&str> =
                    s.warnings.iter().map(|w| w.strip_prefix(&format!("{what}: ")).unwrap_or(w)).collect();
                format!("ok, {} lights, warnings: {}", s.lights.len(), w.join(" | "))
            }
        };
        println!("{name:<75} {num_errors:>6}  {outcome}");
        let Ok(scene) = &result else { continue }; // rejected: every error is matched
        if num_errors == 0 {
            continue;
        }
        let mut pointers: Vec<&str> = scene.warnings.iter().map(|w| warning_pointer(w, &what)).collect();
        for (code, pointer, message) in errors {
            match pointers.iter().position(|p| *p == pointer) {
                Some(k) => {
                    pointers.swap_remove(k);
                }
                None => unmatched.push(format!("{name}: {code} at {pointer} ({message})")),
            }
        }
    }
    assert!(unmatched.is_empty(), "validator errors without a warning at their pointer:\n{}", unmatched.join("\n"));
}

#[test]
fn validator_spot_angles_are_fixed_and_directional_range_dropped() {
    let dir = gltf_dir();
    let light_dir = dir.join("khronos-validator/KHR_lights_punctual/data");
    // Lights not attached to a node are not placed, so attach them by loading a copy with a node.
    let attach = |file: &str| -> GltfScene {
        let mut json: Value = serde_json::from_slice(&std::fs::read(light_dir.join(file)).unwrap()).unwrap();
        json["nodes"] = json!([{ "extensions": { "KHR_lights_punctual": { "light": 0 } } }]);
        load_gltf_from_bytes(&serde_json::to_vec(&json).unwrap(), None, file).unwrap()
    };
    let spot = attach("light/spot_invalid_angles.gltf");
    assert_eq!(spot.lights[0].kind, LightKind::Spot { inner_cone_angle: 0.1, outer_cone_angle: 0.1 });
    let directional = attach("light/directional_light_with_range.gltf");
    assert_eq!((directional.lights[0].kind, directional.lights[0].range), (LightKind::Directional, None));
    assert!(directional.warnings.iter().any(|w| w.contains("range is ignored")));
    let valid = attach("light/valid.gltf");
    let l = &valid.lights[0];
    assert_eq!(l.kind, LightKind::Spot { inner_cone_angle: 0.2, outer_cone_angle: 1.0 });
    assert_eq!((l.color, l.intensity, l.range), (Vec3::new(0.75, 0.3, 1.0), 2.45, Some(10.0)));
    assert!(valid.warnings.is_empty(), "{:?}", valid.warnings);
    let node = load_ok(&light_dir.join("node/valid.gltf"));
    assert_eq!(node.lights.len(), 1);
    assert_eq!(
        (node.lights[0].kind, node.lights[0].intensity, node.lights[0].color),
        (LightKind::Point, 1.0, Vec3::ONE)
    );
}

// ---- Broken files made here ----

/// The binary data of one triangle: 3 positions (36 bytes), 3 uvs (24 bytes), 3 u16 indices (6 bytes).
fn triangle_bin(positions: [[f32; 3]; 3]) -> Vec<u8> {
    let mut bin = Vec::new();
    positions.iter().flatten().for_each(|x| bin.extend_from_slice(&x.to_le_bytes()));
    [0.0f32, 0.0, 1.0, 0.0, 0.0, 1.0].iter().for_each(|x| bin.extend_from_slice(&x.to_le_bytes()));
    [0u16, 1, 2].iter().for_each(|i| bin.extend_from_slice(&i.to_le_bytes()));
    bin
}

const TRIANGLE: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

/// A one-triangle glTF whose buffer is `buffer_uri` declaring `byte_length` bytes, with a material using images
/// `base_color_uri` (base colour) and `mr_uri` (metallic-roughness).
fn triangle_json(buffer_uri: &str, byte_length: usize, base_color_uri: &str, mr_uri: &str) -> Value {
    json!({
        "asset": { "version": "2.0" },
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": [
            { "name": "parent", "translation": [1.0, 2.0, 3.0], "children": [1] },
            { "mesh": 0, "scale": [2.0, 2.0, 2.0] }
        ],
        "meshes": [{ "primitives": [
            { "attributes": { "POSITION": 0, "TEXCOORD_0": 1 }, "indices": 2, "material": 0 }
        ] }],
        "materials": [{
            "name": "textured",
            "pbrMetallicRoughness": {
                "baseColorFactor": [0.5, 0.25, 1.0, 1.0],
                "baseColorTexture": { "index": 0 },
                "metallicRoughnessTexture": { "index": 1 }
            }
        }],
        "textures": [{ "source": 0 }, { "source": 1 }],
        "images": [{ "uri": base_color_uri }, { "uri": mr_uri }],
        "buffers": [{ "uri": buffer_uri, "byteLength": byte_length }],
        "bufferViews": [
            { "buffer": 0, "byteOffset": 0, "byteLength": 36 },
            { "buffer": 0, "byteOffset": 36, "byteLength": 24 },
            { "buffer": 0, "byteOffset": 60, "byteLength": 6 }
        ],
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3" },
            { "bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2" },
            { "bufferView": 2, "componentType": 5123, "count": 3, "type": "SCALAR" }
        ]
    })
}

fn write_json(path: &Path, json: &Value) {
    std::fs::write(path, serde_json::to_vec_pretty(json).unwrap()).unwrap();
}

/// Writes a 2x2 8-bit RGB PNG whose every texel is `rgb`.
fn write_png(path: &Path, rgb: [u8; 3]) {
    image::RgbImage::from_pixel(2, 2, image::Rgb(rgb)).save(path).unwrap();
}

#[test]
fn textured_triangle_loads_with_textures_and_transforms() {
    let dir = temp_dir("textured");
    std::fs::write(dir.join("tri.bin"), triangle_bin(TRIANGLE)).unwrap();
    write_png(&dir.join("base.png"), [255, 128, 0]);
    write_png(&dir.join("mr.png"), [0, 128, 255]);
    write_json(&dir.join("tri.gltf"), &triangle_json("tri.bin", 66, "base.png", "mr.png"));
    let scene = load_ok(&dir.join("tri.gltf"));
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let p = &scene.meshes[0].primitives[0];
    assert_eq!((p.positions.len(), p.indices.as_slice()), (3, &[0, 1, 2][..]));
    assert_eq!(p.uvs.as_ref().unwrap()[1], glam::Vec2::new(1.0, 0.0));
    // World = T(1, 2, 3) * S(2): vertex (1, 0, 0) lands at (3, 2, 3).
    let world = scene.instances[0].world;
    assert_eq!(world.transform_point3(Vec3::X), Vec3::new(3.0, 2.0, 3.0));
    let m = &scene.materials[0];
    assert_eq!(m.base_color, Vec4::new(0.5, 0.25, 1.0, 1.0));
    // Base colour is sRGB-decoded (128 -> 0.2158605, IEC 61966-2-1); metallic-roughness stays linear (128/255).
    let base = &scene.textures[m.base_color_texture.unwrap()];
    assert!((base.get(0, 0) - Vec3::new(1.0, 0.2158605, 0.0)).abs().max_element() < 1e-5, "{}", base.get(0, 0));
    let mr = &scene.textures[m.metallic_roughness_texture.unwrap()];
    assert!((mr.get(1, 1) - Vec3::new(0.0, 128.0 / 255.0, 1.0)).abs().max_element() < 1e-5, "{}", mr.get(1, 1));
}

#[test]
fn missing_and_garbage_textures_leave_factors_and_geometry() {
    let dir = temp_dir("bad-textures");
    std::fs::write(dir.join("tri.bin"), triangle_bin(TRIANGLE)).unwrap();
    let mut rng = SplitMix64::new(7);
    let garbage: Vec<u8> = (0..500).map(|_| rng.next_u64() as u8).collect();
    std::fs::write(dir.join("garbage.png"), garbage).unwrap();
    write_json(&dir.join("tri.gltf"), &triangle_json("tri.bin", 66, "no_such_texture.png", "garbage.png"));
    let scene = load_ok(&dir.join("tri.gltf"));
    let m = &scene.materials[0];
    assert_eq!((m.base_color_texture, m.metallic_roughness_texture), (None, None));
    assert_eq!(m.base_color, Vec4::new(0.5, 0.25, 1.0, 1.0));
    assert_eq!(scene.meshes[0].primitives[0].indices.len(), 3);
    assert_eq!(scene.instances.len(), 1);
    assert!(
        scene.warnings.iter().any(|w| w.contains("no_such_texture.png") && w.contains("not found")),
        "{:?}",
        scene.warnings
    );
    assert!(scene.warnings.iter().any(|w| w.contains("garbage.png")), "{:?}", scene.warnings);
    assert_eq!(scene.warnings.len(), 2, "{:?}", scene.warnings);
}

#[test]
fn unsupported_image_types_and_uv_sets_warn() {
    let dir = temp_dir("ktx2");
    std::fs::write(dir.join("tri.bin"), triangle_bin(TRIANGLE)).unwrap();
    std::fs::write(dir.join("tex.ktx2"), b"\xABKTX 20\xBB\r\n\x1A\n").unwrap();
    let mut json = triangle_json("tri.bin", 66, "tex.ktx2", "tex.ktx2");
    json["images"][0]["mimeType"] = json!("image/ktx2");
    json["materials"][0]["pbrMetallicRoughness"]["metallicRoughnessTexture"]["texCoord"] = json!(1);
    write_json(&dir.join("tri.gltf"), &json);
    let scene = load_ok(&dir.join("tri.gltf"));
    assert_eq!(scene.materials[0].base_color_texture, None);
    assert!(scene.warnings.iter().any(|w| w.contains("tex.ktx2") && w.contains("KTX2")), "{:?}", scene.warnings);
    assert!(scene.warnings.iter().any(|w| w.contains("UV set 1")), "{:?}", scene.warnings);
}

/// KTX2 textures (KHR_texture_basisu, or an image that is KTX2 by mimeType, .ktx2 uri or data: URI) are named as
/// such, with the material and the texture slot that goes without and the factors it keeps; a texture with a
/// PNG `source` beside its KHR_texture_basisu one uses the PNG, as the extension intends.
#[test]
fn ktx2_textures_are_named_with_their_material_and_slot() {
    let dir = temp_dir("ktx2-named");
    let magic = b"\xABKTX 20\xBB\r\n\x1A\n";
    std::fs::write(dir.join("tex.ktx2"), magic).unwrap();
    std::fs::write(dir.join("rough.ktx2"), magic).unwrap();
    write_png(&dir.join("fallback.png"), [255, 255, 255]);
    let json = json!({
        "asset": { "version": "2.0" },
        "extensionsUsed": ["KHR_texture_basisu"],
        "materials": [
            {
                "name": "painted",
                "pbrMetallicRoughness": {
                    "baseColorTexture": { "index": 0 },
                    "metallicRoughnessTexture": { "index": 1 }
                },
                "emissiveFactor": [1.0, 1.0, 1.0],
                "emissiveTexture": { "index": 2 }
            },
            { "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 } }, "emissiveTexture": { "index": 3 } }
        ],
        "textures": [
            { "extensions": { "KHR_texture_basisu": { "source": 0 } } },
            { "source": 1 },
            { "source": 2 },
            { "source": 3, "extensions": { "KHR_texture_basisu": { "source": 0 } } }
        ],
        "images": [
            { "uri": "tex.ktx2", "mimeType": "image/ktx2" },
            { "uri": "rough.ktx2" },
            { "uri": format!("data:image/ktx2;base64,{}", base64_encode(magic)) },
            { "uri": "fallback.png" }
        ]
    });
    let path = dir.join("ktx2.gltf");
    write_json(&path, &json);
    let scene = load_ok(&path);
    let what = path.display().to_string();
    for w in &scene.warnings {
        println!("{w}");
    }
    let painted = &scene.materials[0];
    assert_eq!(
        (painted.base_color_texture, painted.metallic_roughness_texture, painted.emissive_texture),
        (None, None, None)
    );
    assert_eq!((painted.base_color, painted.emissive), (Vec4::ONE, Vec3::ONE), "factors kept");
    assert!(scene.materials[1].emissive_texture.is_some(), "the PNG source beside KHR_texture_basisu is used");
    let expect = [
        ("/materials/0/pbrMetallicRoughness/baseColorTexture", "material 0 \"painted\"", "baseColorFactor"),
        ("/materials/0/pbrMetallicRoughness/metallicRoughnessTexture", "material 0 \"painted\"", "metallicFactor"),
        ("/materials/0/emissiveTexture", "material 0 \"painted\"", "emissiveFactor"),
        ("/materials/1/pbrMetallicRoughness/baseColorTexture", "material 1", "baseColorFactor"),
    ];
    for (pointer, material, factor) in expect {
        let slot = pointer.rsplit('/').next().unwrap();
        assert!(
            scene.warnings.iter().any(|w| warning_pointer(w, &what) == pointer
                && w.contains("KTX2 (Basis Universal, KHR_texture_basisu) textures are not supported")
                && w.contains(material)
                && w.contains(slot)
                && w.contains(factor)),
            "no KTX2 warning at {pointer} naming {material}, {slot} and {factor}: {:#?}",
            scene.warnings
        );
    }
    assert!(!scene.warnings.iter().any(|w| w.contains("unsupported image type")), "{:#?}", scene.warnings);
    // The four above and /extensionsUsed (KHR_texture_basisu is not read).
    assert_eq!(scene.warnings.len(), 5, "{:#?}", scene.warnings);
}

#[test]
fn missing_bin_is_an_error_naming_it() {
    let dir = temp_dir("missing-bin");
    write_json(&dir.join("tri.gltf"), &triangle_json("missing.bin", 66, "a.png", "b.png"));
    let err = load_gltf(&dir.join("tri.gltf")).unwrap_err();
    assert!(matches!(err, GltfError::BufferMissing { .. }), "{err}");
    assert!(err.to_string().contains("missing.bin") && err.to_string().contains("tri.gltf"), "{err}");
}

#[test]
fn buffer_shorter_than_declared_is_an_error() {
    let dir = temp_dir("short-bin");
    std::fs::write(dir.join("tri.bin"), triangle_bin(TRIANGLE)).unwrap();
    write_json(&dir.join("tri.gltf"), &triangle_json("tri.bin", 80, "a.png", "b.png"));
    let err = load_gltf(&dir.join("tri.gltf")).unwrap_err();
    assert!(matches!(err, GltfError::BufferTooShort { declared: 80, actual: 66, .. }), "{err}");
    assert!(err.to_string().contains("tri.bin"), "{err}");
}

#[test]
fn accessor_out_of_bounds_is_an_error() {
    let mut json = triangle_json("", 66, "a.png", "b.png");
    let bin = triangle_bin(TRIANGLE);
    json["buffers"][0]["uri"] = json!(format!("data:application/octet-stream;base64,{}", base64_encode(&bin)));
    // Data-URI buffer, no base directory: loads (external images only warn).
    let scene = load_gltf_from_bytes(&serde_json::to_vec(&json).unwrap(), None, "inline.gltf").unwrap();
    assert_eq!(scene.meshes[0].primitives[0].positions.len(), 3);
    assert!(scene.warnings.iter().any(|w| w.contains("no base directory")), "{:?}", scene.warnings);

    json["accessors"][0]["count"] = json!(4);
    let err = load_gltf_from_bytes(&serde_json::to_vec(&json).unwrap(), None, "inline.gltf").unwrap_err();
    assert!(matches!(&err, GltfError::OutOfBounds { pointer, .. } if pointer == "/accessors/0"), "{err}");
    json["accessors"][0]["count"] = json!(3);
    json["bufferViews"][2]["byteLength"] = json!(600);
    let err = load_gltf_from_bytes(&serde_json::to_vec(&json).unwrap(), None, "inline.gltf").unwrap_err();
    assert!(matches!(&err, GltfError::OutOfBounds { pointer, .. } if pointer == "/bufferViews/2"), "{err}");
    json["bufferViews"][2]["byteLength"] = json!(6);
    json["bufferViews"][0]["byteStride"] = json!(4);
    let err = load_gltf_from_bytes(&serde_json::to_vec(&json).unwrap(), None, "inline.gltf").unwrap_err();
    assert!(err.to_string().contains("byteStride 4"), "{err}");
}

#[test]
fn nan_vertices_drop_their_triangles() {
    let dir = temp_dir("nan");
    let mut positions = [[0.0f32; 3]; 6];
    positions[..3].copy_from_slice(&TRIANGLE);
    positions[3..].copy_from_slice(&[[0.0, 0.0, 1.0], [f32::NAN, 0.0, 1.0], [0.0, 1.0, 1.0]]);
    let mut bin = Vec::new();
    positions.iter().flatten().for_each(|x| bin.extend_from_slice(&x.to_le_bytes()));
    std::fs::write(dir.join("nan.bin"), &bin).unwrap();
    let json = json!({
        "asset": { "version": "2.0" },
        "nodes": [{ "mesh": 0 }],
        "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0 } }] }],
        "buffers": [{ "uri": "nan.bin", "byteLength": 72 }],
        "bufferViews": [{ "buffer": 0, "byteLength": 72 }],
        "accessors": [{ "bufferView": 0, "componentType": 5126, "count": 6, "type": "VEC3" }]
    });
    write_json(&dir.join("nan.gltf"), &json);
    let scene = load_ok(&dir.join("nan.gltf"));
    assert_eq!(scene.meshes[0].primitives[0].indices, vec![0, 1, 2]);
    assert!(scene.warnings.iter().any(|w| w.contains("1 triangle(s) with NaN")), "{:?}", scene.warnings);
    // The unused NaN vertex is replaced, so every position is finite as documented.
    assert!(scene.meshes[0].primitives[0].positions.iter().all(|p| p.is_finite()));
}

#[test]
fn truncated_glb_and_bad_json_are_errors() {
    let dir = gltf_dir();
    let bytes = std::fs::read(dir.join("bevy/CornellBox.glb")).unwrap();
    let tmp = temp_dir("truncated");
    for cut in [6, 12, 19, bytes.len() / 2, bytes.len() - 1] {
        std::fs::write(tmp.join("cut.glb"), &bytes[..cut]).unwrap();
        let err = load_gltf(&tmp.join("cut.glb")).unwrap_err();
        assert!(matches!(err, GltfError::Glb { .. }), "cut at {cut}: {err}");
        assert!(err.to_string().contains("cut.glb"), "{err}");
    }
    let err = load_gltf_from_bytes(b"{\n  \"asset\": {\"version\": \"2.0\"},\n  \"nodes\": [,]\n}", None, "bad.gltf")
        .unwrap_err();
    assert!(matches!(err, GltfError::JsonSyntax { line: 3, .. }), "{err}");
    let err = load_gltf_from_bytes(br#"{"asset": {"version": "1.0"}}"#, None, "old.gltf").unwrap_err();
    assert!(matches!(err, GltfError::Version { .. }), "{err}");
    let err = load_gltf(&tmp.join("nowhere.glb")).unwrap_err();
    assert!(matches!(err, GltfError::NotFound { .. }), "{err}");
}

/// A real .gltf next to a truncated (or empty) copy of its .bin: an error naming both files and both lengths.
#[test]
fn real_gltf_with_truncated_bin_is_an_error_naming_it() {
    let dir = gltf_dir();
    let src = dir.join("renderling");
    let bin = std::fs::read(src.join("shadow_mapping_sanity.bin")).unwrap();
    let tmp = temp_dir("truncated-bin");
    std::fs::copy(src.join("shadow_mapping_sanity.gltf"), tmp.join("scene.gltf")).unwrap();
    for cut in [0, 1, bin.len() / 2, bin.len() - 1] {
        std::fs::write(tmp.join("shadow_mapping_sanity.bin"), &bin[..cut]).unwrap();
        let err = load_gltf(&tmp.join("scene.gltf")).unwrap_err();
        let declared = bin.len() as u64;
        assert!(
            matches!(err, GltfError::BufferTooShort { declared: d, actual, .. } if d == declared && actual == cut as u64),
            "cut at {cut}: {err}"
        );
        let msg = err.to_string();
        assert!(msg.contains("scene.gltf") && msg.contains("shadow_mapping_sanity.bin"), "{msg}");
    }
    // The whole .bin loads.
    std::fs::write(tmp.join("shadow_mapping_sanity.bin"), &bin).unwrap();
    assert!(!load_ok(&tmp.join("scene.gltf")).instances.is_empty());
}

/// Random byte flips and truncations of real files never panic (each gives a scene or an error).
#[test]
fn mutated_files_never_panic() {
    let dir = gltf_dir();
    let mut rng = SplitMix64::new(2024);
    for file in ["bevy/CornellBox.glb", "kajiya/emissive_triangle/triangle.glb", "renderling/spot_lights.glb"] {
        let original = std::fs::read(dir.join(file)).unwrap();
        let (mut loaded, mut failed) = (0, 0);
        for _ in 0..300 {
            let mut bytes = original.clone();
            for _ in 0..1 + rng.below(4) {
                let at = rng.below(bytes.len());
                bytes[at] = rng.next_u64() as u8;
            }
            if rng.below(4) == 0 {
                bytes.truncate(rng.below(bytes.len()));
            }
            match load_gltf_from_bytes(&bytes, None, file) {
                Ok(_) => loaded += 1,
                Err(_) => failed += 1,
            }
        }
        println!("{file}: {loaded} mutated copies loaded, {failed} refused");
    }
}

fn base64_encode(bytes: &[u8]) -> String {
    use base64::Engine;
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

/// A data: URI holding `bytes`.
fn data_uri(bytes: &[u8]) -> String {
    format!("data:application/octet-stream;base64,{}", base64_encode(bytes))
}

#[test]
fn hard_cases_strips_points_cycles_and_bad_references() {
    // Four vertices of a unit square, used as a strip, as points and as a list with an index out of range.
    let mut bin = Vec::new();
    [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]]
        .iter()
        .flatten()
        .for_each(|x| bin.extend_from_slice(&x.to_le_bytes()));
    [0u16, 1, 2, 2, 1, 9].iter().for_each(|i| bin.extend_from_slice(&i.to_le_bytes()));
    let json = json!({
        "asset": { "version": "2.0" },
        "scenes": [{ "nodes": [0, 5] }],
        "nodes": [{ "children": [1] }, { "mesh": 0, "children": [0, 2] }, { "mesh": 3 }],
        "meshes": [{ "primitives": [
            { "attributes": { "POSITION": 0 }, "mode": 5 },
            { "attributes": { "POSITION": 0 }, "mode": 0 },
            { "attributes": { "POSITION": 0 }, "indices": 1, "material": 7 },
            { "attributes": { "NORMAL": 0 } }
        ] }],
        "buffers": [{ "uri": data_uri(&bin), "byteLength": bin.len() }],
        "bufferViews": [{ "buffer": 0, "byteLength": 48 }, { "buffer": 0, "byteOffset": 48, "byteLength": 12 }],
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3" },
            { "bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR" }
        ]
    });
    let scene = load_gltf_from_bytes(&serde_json::to_vec(&json).unwrap(), None, "hard.gltf").unwrap();
    let prims = &scene.meshes[0].primitives;
    assert_eq!(prims.len(), 2, "{:?}", scene.warnings);
    assert_eq!(prims[0].indices, vec![0, 1, 2, 1, 3, 2]); // strip, winding kept
    assert_eq!((prims[1].indices.as_slice(), prims[1].material), (&[0, 1, 2][..], None));
    assert_eq!(scene.instances.len(), 1);
    let expect = [
        "/meshes/0/primitives/1: mode Points",
        "/meshes/0/primitives/2: 1 triangle(s) with vertex indices >= 4",
        "/meshes/0/primitives/2/material: material 7 does not exist",
        "/meshes/0/primitives/3: no POSITION",
        "/scenes/0/nodes/1: node 5 does not exist",
        "/nodes/1/children/0: node 0 reached a second time",
        "/nodes/2/mesh: mesh 3 does not exist",
    ];
    for e in expect {
        assert!(scene.warnings.iter().any(|w| w.contains(e)), "no warning {e:?} in {:#?}", scene.warnings);
    }
    assert_eq!(scene.warnings.len(), expect.len(), "{:#?}", scene.warnings);
}

#[test]
fn ies_lights_are_resolved_relative_to_the_file() {
    let dir = temp_dir("ies");
    std::fs::write(dir.join("lamp.ies"), "IESNA:LM-63-2002\nTILT=NONE\n").unwrap();
    let profile = b"IESNA:LM-63-1995\n";
    let json = json!({
        "asset": { "version": "2.0" },
        "extensionsUsed": ["EXT_lights_ies"],
        "extensions": { "EXT_lights_ies": { "lights": [
            { "uri": "lamp.ies" },
            { "uri": "missing.ies" },
            { "bufferView": 0, "mimeType": "application/x-ies-lm-63" }
        ] } },
        "nodes": [
            {
                "translation": [0.0, 3.0, 0.0],
                "extensions": { "EXT_lights_ies": { "light": 0, "multiplier": 2.5, "color": [1.0, 0.5, 0.25] } }
            },
            { "extensions": { "EXT_lights_ies": { "light": 1 } } },
            { "extensions": { "EXT_lights_ies": { "light": 2 } } },
            { "extensions": { "EXT_lights_ies": { "light": 3 } } }
        ],
        "buffers": [{ "uri": data_uri(profile), "byteLength": profile.len() }],
        "bufferViews": [{ "buffer": 0, "byteLength": profile.len() }]
    });
    write_json(&dir.join("ies.gltf"), &json);
    let scene = load_ok(&dir.join("ies.gltf"));
    assert_eq!(scene.lights.len(), 2, "{:#?}", scene.warnings);
    let lamp = &scene.lights[0];
    assert_eq!((lamp.kind, lamp.intensity, lamp.color), (LightKind::Ies, 2.5, Vec3::new(1.0, 0.5, 0.25)));
    assert_eq!(lamp.world.translation, glam::Vec3A::new(0.0, 3.0, 0.0));
    assert_eq!(lamp.ies, Some(IesSource::File(dir.join("lamp.ies"))));
    match &scene.lights[1].ies {
        Some(IesSource::Embedded { bytes, .. }) => assert_eq!(&bytes[..], profile),
        other => panic!("expected an embedded profile, got {other:?}"),
    }
    assert!(
        scene.warnings.iter().any(|w| w.contains("missing.ies") && w.contains("not found")),
        "{:#?}",
        scene.warnings
    );
    assert!(scene.warnings.iter().any(|w| w.contains("IES light 3 unresolved")), "{:#?}", scene.warnings);
}

/// Numbers in a real file's JSON (indices, counts, offsets, strides, factors) replaced by hostile values never
/// panic: each copy gives a scene or an error.
#[test]
fn mutated_json_numbers_never_panic() {
    let dir = gltf_dir();
    let base = dir.join("renderling");
    let original: Value =
        serde_json::from_slice(&std::fs::read(base.join("shadow_mapping_sanity.gltf")).unwrap()).unwrap();
    /// JSON pointers of every number in `v`.
    fn numbers(v: &Value, at: String, out: &mut Vec<String>) {
        match v {
            Value::Number(_) => out.push(at),
            Value::Array(a) => a.iter().enumerate().for_each(|(i, x)| numbers(x, format!("{at}/{i}"), out)),
            Value::Object(o) => o.iter().for_each(|(k, x)| numbers(x, format!("{at}/{k}"), out)),
            _ => {}
        }
    }
    let mut slots = Vec::new();
    numbers(&original, String::new(), &mut slots);
    let hostile = [
        json!(0),
        json!(1),
        json!(-1),
        json!(3),
        json!(7),
        json!(255),
        json!(65535),
        json!(4294967295u64),
        json!(1e30),
        json!(-0.5),
        json!(0.5),
        json!(5120),
        json!(5125),
        json!(u64::MAX),
    ];
    let mut rng = SplitMix64::new(99);
    let (mut loaded, mut failed) = (0, 0);
    for _ in 0..200 {
        let mut json = original.clone();
        for _ in 0..1 + rng.below(3) {
            let slot = &slots[rng.below(slots.len())];
            *json.pointer_mut(slot).unwrap() = hostile[rng.below(hostile.len())].clone();
        }
        match load_gltf_from_bytes(&serde_json::to_vec(&json).unwrap(), Some(&base), "mutated.gltf") {
            Ok(_) => loaded += 1,
            Err(_) => failed += 1,
        }
    }
    println!("shadow_mapping_sanity.gltf: {loaded} mutated copies loaded, {failed} refused");
    assert!(loaded > 0 && failed > 0);
}

// ---- kelvin's own files (tests/data/gltf/kelvin, written by scripts/make_test_gltf.py) ----

/// Rec. 709 luminance of linear RGB, as kelvin's glTF spawner weighs a light's colour.
fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

/// A world with the lighting systems (every light sampled at every point) and the scene at `path` spawned.
fn spawned(path: &Path) -> (World, Schedule, SpawnReport) {
    let scene = load_ok(path);
    let mut world = World::new();
    let mut schedule = Schedule::default();
    world.insert_resource(Settings { selection: LightSelection::All, ..Default::default() });
    LightingPlugin::build(&mut world, &mut schedule);
    let report = spawn_gltf(&mut world, &scene);
    (world, schedule, report)
}

/// Photometric irradiance (lx) at each of `points` on an upward-facing floor, with its standard error: the mean
/// over `samples` light samples per point of Y(Li) cos / pdf, summed over the lights.
fn floor_irradiance(world: &mut World, schedule: &mut Schedule, points: &[Vec3], samples: u32) -> Vec<(f64, f64)> {
    {
        let mut batch = world.resource_mut::<ShadingBatch>();
        batch.clear();
        for (i, &p) in points.iter().enumerate() {
            for s in 0..samples {
                batch.push(p, Vec3::Y, i as u32, s);
            }
        }
    }
    schedule.run(world);
    let out = world.resource::<DirectLighting>();
    (0..points.len())
        .map(|i| {
            let (mut sum, mut sum2) = (0.0f64, 0.0f64);
            for k in 0..samples as usize {
                let mut e = 0.0f64;
                for j in out.entries(i * samples as usize + k) {
                    let r = out.radiance[j].0;
                    if out.pdf[j] > 0.0 {
                        let y = luminance(Vec3::new(r[0], r[1], r[2]));
                        e += (y * out.wi[j].dot(Vec3::Y).max(0.0) / out.pdf[j]) as f64;
                    }
                }
                sum += e;
                sum2 += e * e;
            }
            let n = samples as f64;
            let mean = sum / n;
            (mean, ((sum2 / n - mean * mean).max(0.0) / n).sqrt())
        })
        .collect()
}

/// EXT_lights_ies with a real profile (ASA_15M_R2.ies): the light's amount is the multiplier times the colour's
/// luminance, as for KHR_lights_punctual lights, so a coloured lamp is as bright as an RGB renderer multiplying
/// colour by intensity shows it, and a black one gives no light (spawned, with zero power; no warning, as for a
/// black point light).
#[test]
fn ies_light_takes_its_colour_luminance() {
    let path = test_data("gltf/kelvin/ies_light_colour.gltf");
    let (mut world, mut schedule, report) = spawned(&path);
    assert!(report.warnings.is_empty(), "{:#?}", report.warnings);
    assert_eq!(report.lights, 2);
    let profile = IesProfile::from_file(&test_data("ies/luxcore/ASA_15M_R2.ies")).unwrap();
    // The file's first candela value (vertical 0, nadir) and the one at vertical 30 degrees, plane C0, both
    // read off the file (its candela multiplier and ballast factor are 1).
    assert_eq!((profile.candela(0.0, 0.0), profile.candela(30.0, 0.0)), (1666.0, 2337.0));
    let colour = Vec3::new(1.0, 0.5, 0.25);
    let multiplier = 2.5;

    let mut lamps: Vec<(GoniometricLight, Transform)> =
        world.query::<(&GoniometricLight, &Transform)>().iter(&world).map(|(g, t)| (g.clone(), *t)).collect();
    lamps.sort_by(|a, b| a.1.translation.x.total_cmp(&b.1.translation.x));
    let [(coloured, at_coloured), (black, at_black)] = &lamps[..] else { panic!("{} IES lights", lamps.len()) };
    assert_eq!((at_coloured.translation, at_black.translation), (Vec3::new(0.0, 3.0, 0.0), Vec3::new(4.0, 3.0, 0.0)));
    let coloured = coloured.resolve(at_coloured).unwrap();
    let black = black.resolve(at_black).unwrap();
    // Candela straight down (the lamp is aimed down): photometric intensity per profile unit times the profile.
    let down = coloured.intensity.luminous() * coloured.profile_value(Vec3::NEG_Y);
    let expected = multiplier * luminance(colour) * 1666.0;
    assert!((down / expected - 1.0).abs() < 1e-3, "{down} cd down, expected {expected} (2.5 x 0.588 x 1666)");
    let black_down = black.intensity.luminous() * black.profile_value(Vec3::NEG_Y);
    assert_eq!((black_down, black.phi()), (0.0, 0.0), "a black IES light emits nothing");

    // Irradiance on the floor, 3 m below: under the coloured lamp, 30 degrees off its axis in plane C0 (local +X,
    // world +X here) and under the black lamp, where only the coloured one (at 53.13 degrees) lights the floor.
    let off_axis = Vec3::new(3.0 * 30f32.to_radians().tan(), 0.0, 0.0);
    let under_black = Vec3::new(4.0, 0.0, 0.0);
    let e = floor_irradiance(&mut world, &mut schedule, &[Vec3::ZERO, off_axis, under_black], 1);
    let scale = (multiplier * luminance(colour)) as f64;
    let cos30 = 30f64.to_radians().cos();
    let cos53 = 0.6;
    let expected = [
        scale * 1666.0 / 9.0,
        scale * 2337.0 * cos30 / (3.0 / cos30).powi(2),
        scale * profile.candela(53.130102, 0.0) * cos53 / 25.0,
    ];
    for (k, ((got, _), want)) in e.iter().zip(expected).enumerate() {
        assert!((got / want - 1.0).abs() < 2e-3, "point {k}: {got} lx, expected {want} lx");
    }
}

/// Lambert's formula: irradiance at `p` (normal +Y) from a convex polygon of radiance `l` (unoccluded).
fn lambert_polygon(vertices: &[Vec3], p: Vec3, l: f64) -> f64 {
    let k = vertices.len();
    let sum: f64 = (0..k)
        .map(|i| {
            let a = (vertices[i] - p).as_dvec3().normalize();
            let b = (vertices[(i + 1) % k] - p).as_dvec3().normalize();
            a.angle_between(b) * glam::DVec3::Y.dot(a.cross(b).normalize())
        })
        .sum();
    sum.abs() * l / 2.0
}

/// glTF 2.0 spec 3.7.4: a node whose world transform has a negative determinant reverses its triangles' winding.
/// mirrored_emitter.gltf has a one-sided emissive quad without NORMAL data and an occluder under scale
/// [-1, 1, 1]; its twin has the same world-space surfaces unmirrored. The emitter faces down and the floor gets the
/// same light from both (the occluder's shadow included).
#[test]
fn mirrored_emitter_faces_and_lights_as_its_unmirrored_twin() {
    let points = [Vec3::new(-0.3, 0.0, 0.0), Vec3::ZERO, Vec3::new(0.4, 0.0, 0.0)];
    let samples = 4096;
    let mut lit = Vec::new();
    for file in ["mirrored_emitter.gltf", "unmirrored_emitter.gltf"] {
        let (mut world, mut schedule, report) = spawned(&test_data("gltf/kelvin").join(file));
        assert!(report.warnings.is_empty(), "{file}: {:#?}", report.warnings);
        assert_eq!((report.meshes, report.emissive_meshes), (3, 1), "{file}");
        let normals: Vec<Vec3> = world
            .query_filtered::<&Mesh, With<AreaLight>>()
            .iter(&world)
            .flat_map(|m| {
                (0..m.triangle_count()).map(|t| {
                    let [a, b, c] = m.triangle(t);
                    (b - a).cross(c - a).normalize()
                })
            })
            .collect();
        assert_eq!(normals.len(), 2, "{file}");
        assert!(normals.iter().all(|n| n.abs_diff_eq(Vec3::NEG_Y, 1e-6)), "{file}: emitter normals {normals:?}");
        lit.push(floor_irradiance(&mut world, &mut schedule, &points, samples));
    }
    // 4 nits over the quad at y = 1; x = 0.4 is outside the occluder's shadow, the others are in part of it.
    let emitter =
        [Vec3::new(-0.5, 1.0, -0.5), Vec3::new(0.5, 1.0, -0.5), Vec3::new(0.5, 1.0, 0.5), Vec3::new(-0.5, 1.0, 0.5)];
    for (k, &p) in points.iter().enumerate() {
        let ((m, m_err), (u, u_err)) = (lit[0][k], lit[1][k]);
        let unoccluded = lambert_polygon(&emitter, p, 4.0);
        println!(
            "x = {}: mirrored {m:.4} +- {m_err:.4}, unmirrored {u:.4} +- {u_err:.4}, unoccluded {unoccluded:.4} lx",
            p.x
        );
        assert!((m - u).abs() < 5.0 * (m_err * m_err + u_err * u_err).sqrt() + 1e-3 * u, "x = {}: {m} vs {u} lx", p.x);
        if k == 2 {
            assert!((m - unoccluded).abs() < 5.0 * m_err + 1e-3 * unoccluded, "x = 0.4: {m} lx, Lambert {unoccluded}");
        } else {
            assert!(m < 0.9 * unoccluded, "x = {}: {m} lx, not shadowed (unoccluded {unoccluded})", p.x);
        }
    }
}

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

#[path = "gltf_import/broken_files.rs"]
mod broken_files;
mod common;
#[path = "gltf_import/kelvin_files.rs"]
mod kelvin_files;
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
    // Bevy's lightmap example: every primitive carries lightmap uvs (TEXCOORD_1) inside [0, 1].
    for p in scene.meshes.iter().flat_map(|m| &m.primitives) {
        let uvs1 = p.uvs1.as_ref().expect("TEXCOORD_1");
        assert_eq!(uvs1.len(), p.positions.len());
        assert!(uvs1.iter().all(|uv| uv.cmpge(glam::Vec2::ZERO).all() && uv.cmple(glam::Vec2::ONE).all()));
    }
    let second_sets = scene.meshes.iter().flat_map(|m| &m.primitives).filter(|p| p.uvs1 != p.uvs).count();
    assert!(second_sets >= 3, "a second set, not a copy of the first ({second_sets} differ)");
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
/// An emissive texture with NaN and negative texels cannot tint an area light: it is dropped
/// (the surface emits its factor uniformly) with one warning naming the material, the texture
/// and how many texels are bad, though two instances use the material; a good texture is kept
/// without a warning.
#[test]
fn an_emissive_texture_with_nan_or_negative_texels_is_dropped_with_a_warning() {
    use glam::Affine3A;
    use kelvin::scene::gltf::{MaterialData, MeshData, MeshInstance, PrimitiveData};
    use kelvin::scene::image::RgbImage;
    use std::sync::Arc;
    let bad = vec![Vec3::ONE, Vec3::new(f32::NAN, 1.0, 1.0), Vec3::new(0.5, -0.1, 0.0), Vec3::splat(-2.0)];
    let good = vec![Vec3::ONE, Vec3::splat(2.0), Vec3::splat(0.5), Vec3::ZERO];
    for (texels, warned) in [(bad, true), (good, false)] {
        let primitive = PrimitiveData {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            normals: None,
            uvs: Some(vec![glam::Vec2::ZERO, glam::Vec2::X, glam::Vec2::Y]),
            uvs1: None,
            indices: vec![0, 1, 2],
            material: Some(0),
        };
        let instance = |x: f32| MeshInstance {
            mesh: 0,
            world: Affine3A::from_translation(Vec3::new(x, 0.0, 0.0)),
            node: None,
            node_name: None,
        };
        let scene = GltfScene {
            meshes: vec![MeshData { name: None, primitives: vec![primitive] }],
            instances: vec![instance(0.0), instance(2.0)],
            materials: vec![MaterialData {
                name: Some("Glow".into()),
                emissive: Vec3::splat(5.0),
                emissive_texture: Some(0),
                ..Default::default()
            }],
            textures: vec![Arc::new(RgbImage { width: 2, height: 2, pixels: texels })],
            ..Default::default()
        };
        let mut w = World::new();
        let report = spawn_gltf(&mut w, &scene);
        assert_eq!(report.emissive_meshes, 2, "{:?}", report.warnings);
        let lights: Vec<AreaLight> = w.query::<&AreaLight>().iter(&w).cloned().collect();
        assert_eq!(lights.len(), 2);
        let mentions: Vec<&String> = report.warnings.iter().filter(|m| m.contains("emissiveTexture")).collect();
        if warned {
            assert_eq!(mentions.len(), 1, "one warning for the material: {:?}", report.warnings);
            let says = mentions[0];
            assert!(says.contains("material 0 \"Glow\"") && says.contains("texture 0"), "{says}");
            assert!(says.contains("1 NaN or infinite and 2 negative texel(s) of 4"), "{says}");
            assert!(lights.iter().all(|l| l.texture.is_none()), "the texture is dropped");
        } else {
            assert!(mentions.is_empty(), "{:?}", report.warnings);
            assert!(lights.iter().all(|l| l.texture.is_some()), "a good texture is kept");
        }
    }
}

//! Inputs that made the fuzz targets (fuzz/, see fuzz/README.md) crash, each rebuilt here in a small form, and
//! the files under tests/fuzz_cases/ replayed through the same paths as the fuzz targets: never a panic, each
//! case gives the documented error or fallback.

use std::path::Path;
use std::sync::Arc;

use bevy_ecs::prelude::*;
use glam::{Vec2, Vec3};
use kelvin::geometry::{MAX_COORDINATE, Mesh, SceneBvh, Transform};
use kelvin::light::{EnvMapTables, GoniometricLight};
use kelvin::scene::gltf::load_gltf_from_bytes;
use kelvin::scene::ies::IesProfile;
use kelvin::scene::image::{ImageError, MAX_PIXELS_PER_BYTE, load_image_from_bytes};
use kelvin::scene::spawn::{SpawnReport, spawn_gltf};
use kelvin::shading::ShadingBatch;
use kelvin::systems::LightingPlugin;
use serde_json::{Value, json};

/// What the `gltf_import` fuzz target does: load, spawn into a World with the plugin, run once with two points.
fn import_and_run(bytes: &[u8], what: &str) -> Option<(World, SpawnReport)> {
    let scene = load_gltf_from_bytes(bytes, None, what).ok()?;
    let mut world = World::new();
    let mut schedule = Schedule::default();
    LightingPlugin::build(&mut world, &mut schedule);
    let report = spawn_gltf(&mut world, &scene);
    let mut batch = world.resource_mut::<ShadingBatch>();
    batch.push(Vec3::ZERO, Vec3::Y, 0, 0);
    batch.push(Vec3::new(0.5, 1.0, -2.0), Vec3::NEG_Z, 1, 0);
    schedule.run(&mut world);
    Some((world, report))
}

/// What the `ies_parse` fuzz target does after a successful parse: flux, a resolved light, its power.
fn resolve_ies(profile: IesProfile) -> (f64, Option<f32>) {
    let flux = profile.integrated_flux_lm();
    let light = GoniometricLight::from_ies(Arc::new(profile)).resolve(&Transform::IDENTITY).ok();
    let phi = light.map(|l| {
        let _ = l.sample_emission_direction(Vec2::new(0.5, 0.5));
        l.phi()
    });
    (flux, phi)
}

/// What the `env_map` fuzz target does: both hints, tables for what loads.
fn load_env(bytes: &[u8], what: &str) -> usize {
    let mut loaded = 0;
    for hint in ["hdr", "exr"] {
        if let Ok(l) = load_image_from_bytes(bytes, hint, what) {
            let tables = EnvMapTables::build(&l.image, true);
            let _ = tables.sample_direction(Vec2::new(0.3, 0.7), true);
            loaded += 1;
        }
    }
    loaded
}

/// A .gltf whose one buffer is a data: URI holding `positions` (f32 VEC3) then `indices` (u32).
fn mesh_gltf(positions: &[Vec3], indices: &[u32]) -> Vec<u8> {
    use base64::Engine;
    let mut bin: Vec<u8> = positions.iter().flat_map(|p| p.to_array()).flat_map(f32::to_le_bytes).collect();
    let index_offset = bin.len();
    bin.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    let uri =
        format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(&bin));
    let json: Value = json!({
        "asset": { "version": "2.0" },
        "nodes": [{ "mesh": 0 }],
        "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0 }, "indices": 1 }] }],
        "buffers": [{ "uri": uri, "byteLength": bin.len() }],
        "bufferViews": [
            { "buffer": 0, "byteLength": index_offset },
            { "buffer": 0, "byteOffset": index_offset, "byteLength": bin.len() - index_offset }
        ],
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": positions.len(), "type": "VEC3" },
            { "bufferView": 1, "componentType": 5125, "count": indices.len(), "type": "SCALAR" }
        ]
    });
    serde_json::to_vec(&json).unwrap()
}

/// gltf_import crash 1: a mutated renderling/cheetah_cone.glb whose sphere had vertices near +-1.2e38 (finite,
/// finite triangle normals) panicked in obvhs's CWBVH conversion (`distribute_left < 7`): the builder's surface
/// areas overflowed f32. Such triangles are now degenerate (src/geometry/triangle.rs, MAX_COORDINATE) and left out
/// of the BVH with a report entry.
#[test]
fn huge_but_finite_vertices_are_left_out_of_the_bvh() {
    let sphere = Mesh::uv_sphere(1.0, 32, 16);
    let mut positions = sphere.positions().to_vec();
    for (i, p) in positions.iter_mut().enumerate().filter(|(i, _)| i % 7 == 3) {
        let huge = if i % 2 == 0 { 1.2e38 } else { -7.3e37 };
        p[i % 3] = huge;
    }
    let gltf = mesh_gltf(&positions, sphere.indices());
    let (world, report) = import_and_run(&gltf, "huge.gltf").expect("loads: the vertices are finite");
    assert_eq!(report.meshes, 1, "{:?}", report.warnings);
    let bvh = world.resource::<SceneBvh>();
    let left_out = bvh.report().degenerate_triangles.len();
    assert!(left_out > 0 && left_out < sphere.triangle_count(), "{left_out} triangles left out");

    // The same straight into the BVH: finite bounds for every node that is kept.
    let mesh = Mesh::new(positions, sphere.indices().to_vec()).unwrap();
    let instance = kelvin::geometry::GeometryInstance {
        geometry: kelvin::geometry::GeometryRef::Mesh(&mesh),
        transform: Transform::IDENTITY,
        entity_index: 0,
        material: 0,
    };
    let bvh = SceneBvh::build(&[instance]);
    assert_eq!(bvh.report().degenerate_triangles.len(), left_out);
    const { assert!(MAX_COORDINATE >= 1e9, "the limit must stay far beyond real scenes") };
}

/// gltf_import crash 2 (the target's invariant check): a primitive whose triangles using a NaN vertex were dropped
/// kept the NaN vertex itself, against `PrimitiveData::positions`' "all finite"; `spawn_gltf` then refused the whole
/// mesh (`Mesh::new` rejects any non-finite vertex) instead of the documented fallback (only those triangles
/// dropped). Fixed in src/scene/gltf/mesh.rs: such vertices are moved onto a kept one.
#[test]
fn nan_vertex_drops_only_its_triangles_through_spawn() {
    let mut positions = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z, Vec3::new(f32::NAN, 1.0, 1.0), Vec3::ONE];
    let gltf = mesh_gltf(&positions, &[0, 1, 2, 3, 4, 5]);
    let scene = load_gltf_from_bytes(&gltf, None, "nan.gltf").unwrap();
    let prim = &scene.meshes[0].primitives[0];
    assert_eq!(prim.indices, vec![0, 1, 2]);
    assert!(prim.positions.iter().all(|p| p.is_finite()), "{:?}", prim.positions);
    let (_, report) = import_and_run(&gltf, "nan.gltf").unwrap();
    assert_eq!((report.meshes, report.triangles), (1, 1), "{:?}", report.warnings);
    // An infinite vertex is handled the same way.
    positions[4] = Vec3::new(0.0, f32::INFINITY, 0.0);
    let (_, report) = import_and_run(&mesh_gltf(&positions, &[0, 1, 2, 3, 4, 5]), "inf.gltf").unwrap();
    assert_eq!((report.meshes, report.triangles), (1, 1), "{:?}", report.warnings);
}

/// ies_parse crash 1 (tests/fuzz_cases/ies_parse/candela_1e81.ies): a candela value of 1.1e81 parses (finite in
/// f64) and integrates to a finite f64 flux, but the resolved light's f32 power was infinite. Fixed in
/// src/light/goniometric.rs: `resolve` refuses profiles whose flux could exceed f32, and any infinite power.
#[test]
fn ies_profile_too_bright_for_f32_is_refused_by_resolve() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_cases/ies_parse/candela_1e81.ies");
    let profile = IesProfile::from_file(&path).expect("a valid LM-63 file");
    assert!(profile.integrated_flux_lm().is_finite() && profile.max_candela() > 1e80);
    let err = GoniometricLight::from_ies(Arc::new(profile)).resolve(&Transform::IDENTITY).unwrap_err();
    assert!(err.to_string().contains("too large for f32"), "{err}");
    // Spawned from a scene it is reported, not panicking: the sync step drops it with a warning.
    let mut world = World::new();
    let mut schedule = Schedule::default();
    LightingPlugin::build(&mut world, &mut schedule);
    let light = GoniometricLight::from_ies(Arc::new(IesProfile::from_file(&path).unwrap()));
    world.spawn((light, Transform::IDENTITY));
    world.resource_mut::<ShadingBatch>().push(Vec3::ZERO, Vec3::Y, 0, 0);
    schedule.run(&mut world);
    assert!(world.resource::<kelvin::light::LightTable>().is_empty());
    let report = world.resource::<kelvin::shading::RunReport>();
    assert!(report.warnings.iter().any(|w| w.contains("too large for f32")), "{:?}", report.warnings);
}

/// env_map crash 1 (tests/fuzz_cases/env_map/b44_overflow.exr, 483 bytes): a B44 block whose deltas underflow
/// made the `exr` crate panic ("attempt to subtract with overflow" where overflow checks are on) inside its
/// own rayon thread pool, which aborts the whole process: the loader's catch_unwind never saw it. Fixed in
/// src/scene/image.rs: EXR blocks are decoded on the calling thread, so such a panic becomes
/// `ImageError::Decode` as documented.
#[test]
fn exr_decoder_panic_is_an_error_not_an_abort() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_cases/env_map/b44_overflow.exr");
    let bytes = std::fs::read(&path).unwrap();
    // With overflow checks (test profile) the decoder panics; without, it may decode wrapped values. Either way
    // the process survives and a loaded image holds only finite, non-negative pixels.
    match load_image_from_bytes(&bytes, "exr", "b44_overflow.exr") {
        Err(e) => {
            assert!(matches!(e, ImageError::Decode { .. }) && e.to_string().contains("b44_overflow.exr"), "{e}");
            eprintln!("{e}");
        }
        Ok(l) => assert!(l.image.pixels.iter().all(|p| p.is_finite() && p.min_element() >= 0.0)),
    }
}

/// env_map, memory: 616 bytes of EXR (tests/fuzz_cases/env_map/exr_claims_50m_pixels.exr) claiming 50331656 x 1
/// pixels made the decoder allocate its buffers (peak RSS 2.1 GB in the fuzzer) before failing on missing data;
/// an HDR header claiming 16000 x 16000 likewise (3 GB). Fixed in src/scene/image.rs: EXR and HDR headers claiming
/// more than MAX_PIXELS_PER_BYTE pixels per byte of file are refused before decoding.
#[test]
fn tiny_files_claiming_huge_images_are_refused_before_decoding() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_cases/env_map/exr_claims_50m_pixels.exr");
    let bytes = std::fs::read(&path).unwrap();
    let err = load_image_from_bytes(&bytes, "exr", "claims.exr").unwrap_err();
    assert!(matches!(err, ImageError::Decode { .. }) && err.to_string().contains("50331656 pixels"), "{err}");
    let mut hdr = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 16000 +X 16000\n".to_vec();
    hdr.extend_from_slice(&[2, 2, 0x3e, 0x80, 0x80, 1, 0x80, 1, 0x80, 1, 0x80, 1]);
    let err = load_image_from_bytes(&hdr, "hdr", "claims.hdr").unwrap_err();
    assert!(matches!(err, ImageError::Decode { .. }) && err.to_string().contains("256000000 pixels"), "{err}");
    const { assert!(MAX_PIXELS_PER_BYTE >= 1024, "real EXR / HDR compression ratios must stay accepted") };
}

/// tile_exr, memory: 665 bytes of tile EXR (tests/fuzz_cases/tile_exr/tile_claims_huge_image.exr) whose display
/// window claims an image of billions of pixels; `merge_tiles` allocated it (12.7 GB) and `kelvin merge` died of
/// it. The merge now refuses images larger than kelvin renders, naming the tile.
#[test]
fn a_tile_claiming_a_huge_image_is_refused_before_merging() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_cases/tile_exr/tile_claims_huge_image.exr");
    let tile = kelvin::render::film_io::read_exr_tile(&path).expect("the tile itself reads");
    assert!(tile.width > 16384 || tile.height > 16384, "{}x{}", tile.width, tile.height);
    let err = kelvin::render::tiles::merge_tiles(&[tile]).unwrap_err().to_string();
    assert!(err.contains("at most 16384 pixels a side"), "{err}");
}

/// tile_exr, memory: 758 bytes of tile EXR (tests/fuzz_cases/tile_exr/tile_window_past_its_bytes.exr) whose data
/// window claims 16384 pixels a side (within kelvin's cap) while its chunks are missing; reading it filled 2.9 GB
/// of pixels before the decoder found the missing bytes. The pixels are now allocated zeroed, pages the read never
/// touches. The process's peak memory (nextest runs each test in a process of its own) says so.
#[test]
fn a_tile_whose_chunks_are_missing_costs_no_memory_for_its_claimed_pixels() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_cases/tile_exr/tile_window_past_its_bytes.exr");
    let err = kelvin::render::film_io::read_exr_tile(&path).unwrap_err().to_string();
    assert!(err.contains("missing bytes"), "{err}");
    #[cfg(target_os = "linux")]
    {
        let status = std::fs::read_to_string("/proc/self/status").unwrap();
        let peak_kb: u64 = status
            .lines()
            .find_map(|l| l.strip_prefix("VmHWM:"))
            .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
            .expect("VmHWM in /proc/self/status");
        assert!(peak_kb < 1 << 20, "peak memory {peak_kb} kB after refusing a 758-byte tile");
    }
}

/// Every file under tests/fuzz_cases/<target>/ goes through its target's path without a panic.
#[test]
fn saved_fuzz_cases_replay_without_panics() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_cases");
    let mut count = 0;
    for target in ["gltf_import", "ies_parse", "env_map", "tile_exr"] {
        let Ok(dir) = std::fs::read_dir(root.join(target)) else { continue };
        let mut files: Vec<_> = dir.flatten().map(|e| e.path()).collect();
        files.sort();
        for path in files {
            let bytes = std::fs::read(&path).unwrap();
            let what = path.file_name().unwrap().to_string_lossy().into_owned();
            match target {
                "gltf_import" => drop(import_and_run(&bytes, &what)),
                "ies_parse" => {
                    if let Ok(p) = IesProfile::parse(&String::from_utf8_lossy(&bytes), &what) {
                        let (flux, phi) = resolve_ies(p);
                        assert!(flux.is_finite() && flux >= 0.0, "{what}: flux {flux}");
                        assert!(phi.is_none_or(|p| p.is_finite() && p >= 0.0), "{what}: power {phi:?}");
                    }
                }
                "tile_exr" => {
                    if let Ok(tile) = kelvin::render::film_io::read_exr_tile_from_bytes(&bytes, &what) {
                        drop(kelvin::render::tiles::merge_tiles(&[tile]));
                    }
                }
                _ => drop(load_env(&bytes, &what)),
            }
            count += 1;
        }
    }
    eprintln!("{count} saved fuzz cases replayed");
}

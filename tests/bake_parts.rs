//! Bakes where options meet: split into parts and merged (bit for bit the whole bake, through the
//! program), texel density choosing each lightmap's side, a volume fitted to a node, and an
//! environment map lighting a bake from the command line.

mod common;

use std::path::Path;
use std::process::Command;

use glam::Vec3;
use kelvin::bake::{LightmapOptions, Part, VolumeOptions, bake_lightmaps, bake_lightmaps_part, merge_lightmaps};
use kelvin::render::job::RenderJob;

use common::files::{TempDir, test_data};
use common::gltf_doc::{Doc, floor};

fn kelvin<S: AsRef<std::ffi::OsStr> + std::fmt::Debug>(args: &[S]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_kelvin")).args(args).output().unwrap()
}

fn ok<S: AsRef<std::ffi::OsStr> + std::fmt::Debug>(args: &[S]) -> String {
    let run = kelvin(args);
    assert!(run.status.success(), "kelvin {args:?}: {}", String::from_utf8_lossy(&run.stderr));
    String::from_utf8_lossy(&run.stdout).into_owned()
}

fn failed<S: AsRef<std::ffi::OsStr> + std::fmt::Debug>(args: &[S]) -> String {
    let run = kelvin(args);
    assert!(!run.status.success(), "kelvin {args:?} succeeded");
    String::from_utf8_lossy(&run.stderr).into_owned()
}

/// Every file of folder `a` and `b` (by name, sorted), with their bytes.
fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file())
        .map(|p| (p.file_name().unwrap().to_string_lossy().into_owned(), std::fs::read(&p).unwrap()))
        .collect();
    out.sort();
    out
}

/// CornellBox's lightmaps baked in three parts on the command line and merged are the whole
/// bake's files byte for byte (EXRs, KTX2s and the index); the parts folder is gone after.
#[test]
fn lightmap_parts_merge_into_the_whole_bake_byte_for_byte() {
    let dir = TempDir::new("bake-parts", "cornell");
    let scene = test_data("gltf/bevy/CornellBox.glb");
    let scene = scene.to_str().unwrap();
    let (whole, split) = (dir.join("whole"), dir.join("split"));
    let base = ["bake", "lightmaps", scene, "--size", "16", "--spp", "4", "--max-depth", "3", "--seed", "5"];
    ok(&[&base[..], &["-o", whole.to_str().unwrap()]].concat());
    let split_args = [&base[..], &["-o", split.to_str().unwrap()]].concat();
    for k in ["3/3", "1/3", "2/3"] {
        let out = ok(&[&split_args[..], &["--part", k]].concat());
        assert!(out.contains(&format!("baked part {} of 3", &k[..1])), "{out}");
    }
    assert_eq!(std::fs::read_dir(split.join("parts")).unwrap().count(), 3);
    ok(&[&split_args[..], &["--merge"]].concat());
    let (a, b) = (files(&whole), files(&split));
    assert_eq!(a.iter().map(|f| &f.0).collect::<Vec<_>>(), b.iter().map(|f| &f.0).collect::<Vec<_>>());
    assert_eq!(a.len(), 9, "four meshes' EXR and KTX2, and the index");
    for ((name, x), (_, y)) in a.iter().zip(&b) {
        assert!(x == y, "{name} differs between the whole bake and the merged parts");
    }
    assert!(!split.join("parts").exists());
}

/// A merge refuses a missing part, a part of another bake (other spp: the differing setting is
/// named), and a time budget cannot be split.
#[test]
fn a_merge_refuses_missing_and_foreign_parts() {
    let dir = TempDir::new("bake-parts", "refuse");
    let scene = test_data("gltf/bevy/CornellBox.glb");
    let out = dir.join("maps");
    let args = ["bake", "lightmaps", scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "--size", "8"];
    let with = |extra: &[&'static str]| -> Vec<String> { args.iter().chain(extra).map(|s| s.to_string()).collect() };
    ok(&with(&["--spp", "2", "--part", "1/2"]));
    let err = failed(&with(&["--spp", "2", "--merge"]));
    assert!(err.contains("are in no part"), "{err}");
    ok(&with(&["--spp", "3", "--part", "2/2"]));
    let err = failed(&with(&["--spp", "2", "--merge"]));
    assert!(err.contains("/settings/command/spp is 2 against 3"), "{err}");
    let err = failed(&with(&["--time", "1", "--part", "1/2"]));
    assert!(err.contains("--time") && err.contains("--part"), "{err}");
    let err = failed(&with(&["--part", "3/2"]));
    assert!(err.contains("1 <= K <= N"), "{err}");
}

/// Through the library, a volume in parts: every side of the merged volume is the whole bake's,
/// and parts of a lightmap bake do not merge into a volume.
#[test]
fn volume_parts_merge_bit_for_bit_and_kinds_do_not_mix() {
    let dir = TempDir::new("bake-parts", "volume");
    let path = dir.join("scene.gltf");
    let mut doc = Doc::default();
    let m = doc.material(0.5, 0.0);
    doc.mesh("floor", &[floor([-1.0, 1.0], [-1.0, 1.0], 0.0, m)]);
    doc.light(serde_json::json!({ "type": "point", "intensity": 5.0 }), Vec3::new(0.2, 1.0, 0.1), [0.0, 0.0, 0.0, 1.0]);
    doc.write(&path);
    let load = || RenderJob { scene: Some(path.clone()), seed: 3, ..RenderJob::default() }.load().unwrap();
    let opts = VolumeOptions {
        resolution: glam::UVec3::new(3, 2, 2),
        spp: 6,
        bounds: Some((Vec3::new(-1.0, 0.1, -1.0), Vec3::new(1.0, 1.1, 1.0))),
        ..VolumeOptions::default()
    };
    let whole = kelvin::bake::bake_volume(&mut load(), &opts, |_| {}).unwrap();
    let parts: Vec<_> = (0..4)
        .map(|index| {
            let part = kelvin::bake::bake_volume_part(&mut load(), &opts, Part { index, count: 4 }, |_| {}).unwrap();
            // Through the file format, as a farm moves them.
            kelvin::bake::BakePart::from_bytes(&part.to_bytes(), "part").unwrap()
        })
        .collect();
    let merged = kelvin::bake::merge_volume(&mut load(), &opts, parts).unwrap();
    assert_eq!(merged.sides, whole.sides);
    assert_eq!(merged.std_error, whole.std_error);
    assert_eq!(merged.state, whole.state);
    let lightmap_opts = LightmapOptions { size: 4, spp: 2, ..LightmapOptions::default() };
    let part = bake_lightmaps_part(&mut load(), &lightmap_opts, Part::WHOLE, |_| {}).unwrap();
    let err = kelvin::bake::merge_volume(&mut load(), &opts, vec![part]).unwrap_err().to_string();
    assert!(err.contains("lightmaps bake"), "{err}");
    let part = bake_lightmaps_part(&mut load(), &lightmap_opts, Part { index: 0, count: 2 }, |_| {}).unwrap();
    let err = merge_lightmaps(&mut load(), &lightmap_opts, vec![part]).unwrap_err().to_string();
    assert!(err.contains("are in no part"), "{err}");
}

/// Texel density picks each mesh's side from its area: a 1 m and a 4 m wide quad at 10 texels per
/// metre get sides 12 (10, rounded up to a multiple of 4) and 40, and the largest side caps them.
#[test]
fn texel_density_sizes_each_lightmap_by_its_area() {
    let dir = TempDir::new("bake-parts", "density");
    let path = dir.join("scene.gltf");
    let mut doc = Doc::default();
    let m = doc.material(0.5, 0.0);
    doc.mesh("small", &[floor([0.0, 1.0], [0.0, 1.0], 0.0, m)]);
    doc.mesh("large", &[floor([2.0, 6.0], [0.0, 4.0], 0.0, m)]);
    doc.light(serde_json::json!({ "type": "point", "intensity": 5.0 }), Vec3::new(1.0, 2.0, 1.0), [0.0, 0.0, 0.0, 1.0]);
    doc.write(&path);
    let load = || RenderJob { scene: Some(path.clone()), ..RenderJob::default() }.load().unwrap();
    let sides = |size, density| {
        let opts = LightmapOptions { size, texels_per_unit: Some(density), spp: 1, ..LightmapOptions::default() };
        let report = bake_lightmaps(&mut load(), &opts, |_| {}).unwrap();
        report.lightmaps.iter().map(|m| (m.name.clone(), m.size)).collect::<Vec<_>>()
    };
    assert_eq!(sides(4096, 10.0), [("small".into(), 12), ("large".into(), 40)]);
    assert_eq!(sides(32, 10.0), [("small".into(), 12), ("large".into(), 32)]);
    let opts = LightmapOptions { texels_per_unit: Some(f32::NAN), ..LightmapOptions::default() };
    let err = bake_lightmaps(&mut load(), &opts, |_| {}).unwrap_err().to_string();
    assert!(err.contains("texels_per_unit = NaN"), "{err}");
}

/// `--node` fits the volume to the meshes a node places (the light probe's transform is their
/// box), an unknown node is an error listing the names there are, and `--env` lights a bake as it
/// lights a render: a floor open to a uniform map of 0.5 at --env-intensity 8 holds E / pi = 4 nit.
#[test]
fn node_bounds_and_an_environment_map_on_the_command_line() {
    let dir = TempDir::new("bake-parts", "node-env");
    let path = dir.join("scene.gltf");
    let mut doc = Doc::default();
    let m = doc.material(0.5, 0.0);
    doc.mesh("floor", &[floor([-1.0, 3.0], [-2.0, 1.0], 0.5, m)]);
    doc.write(&path);
    let env = dir.join("grey.exr");
    kelvin::render::film_io::write_exr(&env, 8, 4, &[Vec3::splat(0.5); 32]).unwrap();
    let scene = path.to_str().unwrap();
    let out = dir.join("maps");
    let args = ["bake", "lightmaps", scene, "-o", out.to_str().unwrap(), "--size", "4", "--spp", "1024", "--env"];
    ok(&[&args[..], &[env.to_str().unwrap(), "--env-intensity", "8"]].concat());
    let (_, _, texels) = kelvin::render::film_io::read_exr(&out.join("floor.exr")).unwrap();
    // 1024 paths per texel leave about 1% noise (MIS of the map's samples and cosine samples).
    for t in &texels {
        assert!((*t - Vec3::splat(4.0)).abs().max_element() < 0.15, "{t}");
    }
    let mean = texels.iter().sum::<Vec3>() / texels.len() as f32;
    assert!((mean - Vec3::splat(4.0)).abs().max_element() < 0.05, "{mean}");
    let volume = dir.join("v.ktx2");
    let args = ["bake", "volume", scene, "-o", volume.to_str().unwrap(), "--resolution", "2,1,2", "--spp", "4"];
    let err = failed(&[&args[..], &["--node", "nothing"]].concat());
    assert!(err.contains("no mesh is placed by a node named \"nothing\"") && err.contains("floor.node"), "{err}");
    // A flat floor has no height: a volume needs a box.
    let err = failed(&[&args[..], &["--node", "floor.node"]].concat());
    assert!(err.contains("no volume"), "{err}");
    let mut doc = Doc::default();
    let m = doc.material(0.5, 0.0);
    doc.mesh("box", &[common::gltf_doc::cuboid(Vec3::new(-1.0, 0.0, 2.0), Vec3::new(1.0, 3.0, 4.0), false, false, m)]);
    doc.write(&path);
    ok(&[&args[..], &["--node", "box.node"]].concat());
    let info: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.join("v.json")).unwrap()).unwrap();
    assert_eq!(info["transform"]["translation"], serde_json::json!([0.0, 1.5, 3.0]));
    assert_eq!(info["transform"]["scale"], serde_json::json!([2.0, 3.0, 2.0]));
}

/// A double-sided lamp has no inside: a floor under its back face is lit by it (a one-sided back
/// face there would be a leak, every sample dropped). The lamp spans nearly the whole hemisphere,
/// so each texel holds about its radiance.
#[test]
fn the_back_of_a_double_sided_lamp_lights_what_it_faces_and_is_no_leak() {
    let dir = TempDir::new("bake-parts", "two-sided");
    let path = dir.join("scene.gltf");
    let bake = |double_sided: bool| {
        let mut doc = Doc::default();
        let (floor_m, lamp_m) = (doc.material(0.5, 0.0), doc.material(0.5, 20.0));
        if double_sided {
            doc.double_sided(lamp_m);
        }
        doc.mesh("floor", &[floor([-1.0, 1.0], [-1.0, 1.0], 0.0, floor_m)]);
        let mut lamp = floor([-200.0, 200.0], [-200.0, 200.0], 0.5, lamp_m);
        lamp.uv1 = None;
        doc.mesh("lamp", &[lamp]);
        doc.write(&path);
        let mut loaded = RenderJob { scene: Some(path.clone()), ..RenderJob::default() }.load().unwrap();
        let opts = LightmapOptions { size: 4, spp: 64, ..LightmapOptions::default() };
        bake_lightmaps(&mut loaded, &opts, |_| {}).unwrap().lightmaps.remove(0)
    };
    let lit = bake(true);
    for (t, s) in lit.texels.iter().zip(&lit.state) {
        assert_eq!(*s, kelvin::bake::TexelState::Baked);
        // E / pi of a 400 m square 0.5 m above: its radiance to 1e-5, plus what the small floor
        // sends up and the lamp's back returns, at most the series 20 / (1 - 0.5 * 0.5) of two
        // infinite planes; 64 paths leave a few percent of noise below.
        assert!((19.0..=20.0 / 0.75).contains(&t.x), "{t}");
    }
    assert_eq!(lit.leaked_samples, 0);
    let one_sided = bake(false);
    assert!(one_sided.leaked_samples == 16 * 64, "every sample meets the lamp's back: {}", one_sided.leaked_samples);
}

/// The room's files written into `dir`, its maps' folder and `kelvin bake lightmaps` of it at 8 px, 2 spp.
fn room_bake(dir: &TempDir) -> (std::path::PathBuf, Vec<String>) {
    let scene = common::room_files::write(&dir.join(""));
    let out = dir.join("maps");
    let args = ["bake", "lightmaps", scene.to_str().unwrap(), "--size", "8", "--spp", "2", "-o", out.to_str().unwrap()];
    (out.clone(), args.map(str::to_owned).to_vec())
}

/// A part whose bytes were damaged on the way (one bit flipped in its sums) is refused by the
/// merge, naming the file, instead of baking wrong light into the maps.
#[test]
fn a_bake_part_with_a_flipped_bit_is_refused() {
    let dir = TempDir::new("bake-parts", "flipped");
    let (out, base) = room_bake(&dir);
    let base: Vec<&str> = base.iter().map(String::as_str).collect();
    ok(&[&base[..], &["--part", "1/2"]].concat());
    ok(&[&base[..], &["--part", "2/2"]].concat());
    let part = out.join("parts/part-1-of-2.kbake");
    let mut bytes = std::fs::read(&part).unwrap();
    // A bit of the last cell's sums, past the header.
    let at = bytes.len() - 32 - 20;
    bytes[at] ^= 0x10;
    std::fs::write(&part, &bytes).unwrap();
    let err = failed(&[&base[..], &["--merge"]].concat());
    assert!(err.contains("part-1-of-2.kbake") && err.contains("checksum"), "{err}");
    assert!(!out.join("lightmaps.json").exists());
}

/// Parts baked from two versions of the scene's buffer (`box.bin` changed between them) do not merge.
#[test]
fn bake_parts_of_another_buffer_are_refused() {
    let dir = TempDir::new("bake-parts", "inputs");
    let (_, base) = room_bake(&dir);
    let base: Vec<&str> = base.iter().map(String::as_str).collect();
    ok(&[&base[..], &["--part", "1/2"]].concat());
    common::room_files::change(&dir.join(""), "box.bin");
    ok(&[&base[..], &["--part", "2/2"]].concat());
    let err = failed(&[&base[..], &["--merge"]].concat());
    assert!(err.contains("was not made by this bake") && err.contains("/inputs/input box.bin"), "{err}");
}

/// A split bake run again bakes only its missing parts, and its merge ignores the parts of
/// another split left in the folder (a part of a split into 3 among those of a split into 2).
#[test]
fn split_bakes_resume_per_part_and_ignore_parts_of_another_split() {
    let dir = TempDir::new("bake-parts", "resume");
    let (out, base) = room_bake(&dir);
    let base: Vec<&str> = base.iter().map(String::as_str).collect();
    ok(&[&base[..], &["--part", "1/3"]].concat());
    ok(&[&base[..], &["--part", "1/2"]].concat());
    let first = std::fs::read(out.join("parts/part-1-of-2.kbake")).unwrap();
    let again = ok(&[&base[..], &["--part", "1/2"]].concat());
    assert!(again.contains("part 1 of 2 is already baked"), "{again}");
    assert_eq!(std::fs::read(out.join("parts/part-1-of-2.kbake")).unwrap(), first);
    ok(&[&base[..], &["--part", "2/2"]].concat());
    let merged = kelvin(&[&base[..], &["--merge"]].concat());
    let log = String::from_utf8_lossy(&merged.stderr);
    assert!(merged.status.success(), "{log}");
    assert!(log.contains("1 parts of a split into 3 ignored"), "{log}");
    assert!(out.join("lightmaps.json").exists());
}

//! `kelvin batch MANIFEST`: jobs render as `kelvin render` would, failing jobs say why while the
//! others complete, the exit code says whether all succeeded, and a rerun skips finished outputs.

mod common;

use std::path::Path;
use std::process::{Command, Output};

use common::files::{TempDir, test_data};

fn kelvin(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_kelvin")).args(args).output().expect("kelvin runs")
}

fn text(out: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr))
}

fn write_manifest(dir: &TempDir, jobs: &str) -> String {
    let path = dir.join("jobs.json");
    std::fs::write(&path, format!("{{\"jobs\": [{jobs}]}}")).unwrap();
    path.to_str().unwrap().to_owned()
}

#[test]
fn batch_renders_good_jobs_reports_bad_ones_and_resumes() {
    let dir = TempDir::new("cli-batch", "resume");
    let cornell = test_data("gltf/bevy/CornellBox.glb");
    let manifest = write_manifest(
        &dir,
        &format!(
            r#"{{"name": "room", "output": "out/room.exr", "size": "23x17", "spp": 2}},
               {{"name": "box", "scene": "{}", "output": "out/box.exr", "size": "20x16", "spp": 3,
                 "settings": {{"color": "spectral", "seed": 9, "light_sampler": "power"}}}},
               {{"name": "lost", "scene": "no/such/scene.glb", "output": "out/lost.exr"}},
               {{"name": "flat", "output": "out/flat.exr", "size": "0x16"}}"#,
            cornell.display()
        ),
    );
    let out = kelvin(&["batch", &manifest]);
    let log = text(&out);
    assert!(!out.status.success(), "two jobs failed: {log}");
    assert!(log.contains("lost") && log.contains("no/such/scene.glb: no such file"), "{log}");
    assert!(log.contains("flat") && log.contains("'0x16'"), "{log}");
    assert!(log.contains("4 jobs: 2 rendered, 0 skipped, 2 failed"), "{log}");

    // Each finished job's EXR is the plain render's, byte for byte.
    let plain = dir.join("plain.exr");
    let p = plain.to_str().unwrap();
    let cornell = cornell.to_str().unwrap();
    for (job, args) in [
        ("room.exr", vec!["render", "-o", p, "--size", "23x17", "--spp", "2"]),
        ("box.exr", vec!["render", "-o", p, "--size", "20x16", "--spp", "3", "--color", "spectral", "--seed", "9"]),
    ] {
        let args = [args, if job == "box.exr" { vec!["--light-sampler", "power", cornell] } else { vec![] }].concat();
        assert!(kelvin(&args).status.success());
        let batch = std::fs::read(dir.join("out").join(job)).unwrap();
        assert!(batch == std::fs::read(&plain).unwrap(), "{job} differs from kelvin render");
        assert!(dir.join("out").join(job).with_extension("png").exists());
    }

    // A rerun skips what is finished; a removed output is rendered again.
    let room = dir.join("out/room.exr");
    let before = std::fs::metadata(&room).unwrap().modified().unwrap();
    std::fs::remove_file(dir.join("out/box.exr")).unwrap();
    let out = kelvin(&["batch", &manifest]);
    let log = text(&out);
    assert!(log.contains("4 jobs: 1 rendered, 1 skipped, 2 failed"), "{log}");
    assert_eq!(std::fs::metadata(&room).unwrap().modified().unwrap(), before, "room.exr was not rewritten");
    assert!(dir.join("out/box.exr").exists());
    // No temporary files are left beside the outputs.
    let names: Vec<_> = std::fs::read_dir(dir.join("out")).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(names.len(), 4, "{names:?}");
}

#[test]
fn a_manifest_of_good_jobs_succeeds_and_plans_as_json() {
    let dir = TempDir::new("cli-batch", "plan");
    let manifest = write_manifest(
        &dir,
        r#"{"output": "a.exr", "size": "8x6", "spp": 1, "camera": {"environment_at": [0, 1, 0]}},
           {"output": "b.png", "size": "5x4", "spp": 1, "settings": {"mis": false, "all_lights": true}},
           {"output": "c.exr", "size": "5x4", "spp": 1, "settings": {"light_sampler": "restir", "exposure": 1.5}}"#,
    );
    let plan = kelvin(&["batch", &manifest, "--plan"]);
    assert!(plan.status.success(), "{}", text(&plan));
    let plan: serde_json::Value = serde_json::from_slice(&plan.stdout).unwrap();
    let a = &plan["jobs"][0];
    assert_eq!((a["width"].as_u64(), a["height"].as_u64(), a["done"].as_bool()), (Some(8), Some(6), Some(false)));
    assert!(Path::new(a["output"].as_str().unwrap()).is_absolute());
    let args: Vec<&str> = a["args"].as_array().unwrap().iter().map(|v| v.as_str().unwrap()).collect();
    assert!(args.windows(2).any(|w| w == ["--environment-at", "0,1,0"]), "{args:?}");
    let b: Vec<&str> = plan["jobs"][1]["args"].as_array().unwrap().iter().map(|v| v.as_str().unwrap()).collect();
    assert!(b.contains(&"--no-mis") && b.contains(&"--all-lights"), "{b:?}");
    // What a driver needs: whether a job tiles, and the exposure `kelvin merge` must be given.
    assert!(a["untileable"].is_null() && a["exposure"].is_null(), "{a}");
    let c = &plan["jobs"][2];
    assert!(c["untileable"].as_str().is_some_and(|why| why.contains("ReSTIR")), "{c}");
    assert_eq!(c["exposure"].as_f64(), Some(1.5));

    let out = kelvin(&["batch", &manifest]);
    assert!(out.status.success(), "{}", text(&out));
    assert!(dir.join("a.exr").exists() && dir.join("b.png").exists());
    assert!(text(&out).contains("3 jobs: 3 rendered, 0 skipped, 0 failed"));
}

#[test]
fn unreadable_manifests_and_unsupported_entries_are_clear_errors() {
    let dir = TempDir::new("cli-batch", "errors");
    let out = kelvin(&["batch", dir.join("none.json").to_str().unwrap()]);
    assert!(!out.status.success() && text(&out).contains("none.json"), "{}", text(&out));
    std::fs::write(dir.join("bad.json"), "{\"jobs\": 3}").unwrap();
    let out = kelvin(&["batch", dir.join("bad.json").to_str().unwrap()]);
    assert!(!out.status.success() && text(&out).contains("bad.json") && !text(&out).contains("panicked"));
    let manifest = write_manifest(
        &dir,
        r#"{"output": "f.exr", "frames": "0..1"}, {"size": "4x4"}, {"output": "g_#.exr", "frames": "3..1"},
           {"output": "h_#.exr", "frames": "2", "size": "4x4", "spp": 1}, {"output": "i.exr", "fps": 30}"#,
    );
    let out = kelvin(&["batch", &manifest]);
    let log = text(&out);
    assert!(log.contains("f.exr: an output for --frames needs a run of '#'"), "{log}");
    assert!(log.contains("missing field `output`"), "{log}");
    assert!(log.contains("frames: '3..1': 1 is before 3"), "{log}");
    assert!(log.contains("--frames: the default scene has no animation"), "{log}");
    assert!(log.contains("fps and animation need frames"), "{log}");
    assert!(log.contains("6 jobs: 0 rendered, 0 skipped, 6 failed"), "{log}");
}

/// A job with frames is planned as one job per frame, each the image `kelvin render --frames`
/// writes for that frame, byte for byte; a rerun skips the frames that exist.
#[test]
fn frames_of_an_animated_scene_are_jobs_of_their_own() {
    let dir = TempDir::new("cli-batch", "frames");
    let scene = test_data("gltf/kelvin/animated_lamp.gltf");
    let job = format!(
        r#"{{"name": "lamp", "scene": "{}", "output": "anim/f_##.exr", "frames": "3..5", "fps": 4,
             "animation": "day", "size": "6x5", "spp": 2, "settings": {{"integrator": "direct"}}}}"#,
        scene.display()
    );
    let manifest = write_manifest(&dir, &job);
    let plan = kelvin(&["batch", &manifest, "--plan"]);
    let plan: serde_json::Value = serde_json::from_slice(&plan.stdout).unwrap();
    let names: Vec<&str> = plan["jobs"].as_array().unwrap().iter().map(|j| j["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["lamp frame 3", "lamp frame 4", "lamp frame 5"]);
    let out = kelvin(&["batch", &manifest]);
    assert!(out.status.success() && text(&out).contains("3 jobs: 3 rendered"), "{}", text(&out));

    let one = dir.join("one_#.exr");
    let scene = scene.to_str().unwrap();
    let args =
        ["render", scene, "--frames", "3..5", "--fps", "4", "--size", "6x5", "--spp", "2", "--integrator", "direct"];
    let out = kelvin(&[&args[..], &["-o", one.to_str().unwrap()]].concat());
    assert!(out.status.success() && text(&out).contains("frame 5 (t = 1.2500 s)"), "{}", text(&out));
    for k in 3..=5 {
        let batch = std::fs::read(dir.join(format!("anim/f_0{k}.exr"))).unwrap();
        assert!(batch == std::fs::read(dir.join(format!("one_{k}.exr"))).unwrap(), "frame {k} differs");
    }
    let p = kelvin::render::film_io::read_exr_provenance(&dir.join("anim/f_03.exr")).unwrap();
    assert_eq!((p.0["frame"].as_str(), p.0["animation"].as_str(), p.0["animation_name"].as_str()), ("3", "0", "day"));
    std::fs::remove_file(dir.join("anim/f_04.exr")).unwrap();
    let out = kelvin(&["batch", &manifest]);
    assert!(text(&out).contains("3 jobs: 1 rendered, 2 skipped, 0 failed"), "{}", text(&out));
}

/// Bake jobs: a lightmap bake in three parts and a volume, each byte for byte what `kelvin bake`
/// writes alone; bad bake jobs fail with the cause (an unknown flag as the command line says it,
/// parts out of range, a time budget split) while the others run; a rerun skips finished bakes.
#[test]
fn batch_bakes_in_parts_byte_for_byte() {
    let dir = TempDir::new("cli-batch", "bake");
    let cornell = test_data("gltf/bevy/CornellBox.glb");
    let manifest = write_manifest(
        &dir,
        &format!(
            r#"{{"name": "maps", "bake": "lightmaps", "scene": "{c}", "output": "out/maps", "parts": 3,
                 "settings": {{"size": 16, "spp": 4, "max_depth": 2, "seed": 3}}}},
               {{"name": "probe", "bake": "volume", "scene": "{c}", "output": "out/probe.ktx2",
                 "settings": {{"resolution": [2, 2, 3], "spp": 4}}}},
               {{"name": "typo", "bake": "lightmaps", "scene": "{c}", "output": "out/typo", "settings": {{"sise": 8}}}},
               {{"name": "many", "bake": "volume", "scene": "{c}", "output": "out/many.ktx2", "parts": 0}},
               {{"name": "timed", "bake": "lightmaps", "scene": "{c}", "output": "out/timed", "parts": 2,
                 "settings": {{"time": 1}}}}"#,
            c = cornell.display()
        ),
    );
    let out = kelvin(&["batch", &manifest]);
    let log = text(&out);
    assert!(!out.status.success(), "{log}");
    assert!(log.contains("typo") && log.contains("unexpected argument '--sise'"), "{log}");
    assert!(log.contains("many") && log.contains("parts: 0 is not a whole number"), "{log}");
    assert!(log.contains("timed") && log.contains("cannot be used with"), "{log}");
    assert!(log.contains("5 jobs: 2 rendered, 0 skipped, 3 failed"), "{log}");
    let c = cornell.to_str().unwrap();
    let plain = dir.join("plain");
    let p = plain.to_str().unwrap();
    let args = ["bake", "lightmaps", c, "-o", p, "--size", "16", "--spp", "4", "--max-depth", "2", "--seed", "3"];
    assert!(kelvin(&args).status.success());
    let mut names: Vec<_> = std::fs::read_dir(&plain).unwrap().map(|e| e.unwrap().file_name()).collect();
    names.sort();
    assert_eq!(names.len(), 9);
    for name in names {
        let (a, b) = (std::fs::read(plain.join(&name)).unwrap(), std::fs::read(dir.join("out/maps").join(&name)));
        assert!(b.is_ok_and(|b| b == a), "{name:?} differs from kelvin bake's");
    }
    assert!(!dir.join("out/maps/parts").exists());
    let volume = dir.join("plain.ktx2");
    let args = ["bake", "volume", c, "-o", volume.to_str().unwrap(), "--resolution", "2,2,3", "--spp", "4"];
    assert!(kelvin(&args).status.success());
    assert!(std::fs::read(&volume).unwrap() == std::fs::read(dir.join("out/probe.ktx2")).unwrap());
    let plan = text(&kelvin(&["batch", &manifest, "--plan"]));
    let plan: serde_json::Value = serde_json::from_str(&plan).unwrap();
    assert_eq!(plan["jobs"][0]["command"], "bake");
    assert_eq!(plan["jobs"][0]["parts"], 3);
    assert_eq!(plan["jobs"][0]["done"], true);
    let again = text(&kelvin(&["batch", &manifest]));
    assert!(again.contains("5 jobs: 0 rendered, 2 skipped, 3 failed"), "{again}");
    // The plan names each input with its digest, for a farm to check every machine holds the same.
    let digest = kelvin::provenance::file_sha256(&cornell).unwrap();
    assert_eq!(plan["jobs"][0]["inputs"][cornell.to_str().unwrap()], digest.as_str());
    // A finished bake is finished for its own settings only: the index records them.
    let changed = std::fs::read_to_string(&manifest).unwrap().replace(r#""spp": 4"#, r#""spp": 5"#);
    std::fs::write(&manifest, changed).unwrap();
    let plan: serde_json::Value = serde_json::from_str(&text(&kelvin(&["batch", &manifest, "--plan"]))).unwrap();
    for (k, what) in [(0, "/settings/command/spp is 5 against 4"), (1, "/settings/command/spp is 5 against 4")] {
        assert_eq!(plan["jobs"][k]["done"], false, "{}", plan["jobs"][k]);
        assert!(plan["jobs"][k]["stale"].as_str().unwrap().contains(what), "{}", plan["jobs"][k]);
    }
}

/// `--plan` finds what it can before any work: two jobs writing one output (both named), an
/// output kelvin cannot write, a volume not written as .ktx2; farm frame lists plan one entry per
/// frame; `--task N` runs plan entry N alone, as a farm's task runner calls it.
#[test]
fn plan_checks_outputs_and_task_runs_one_entry() {
    let dir = TempDir::new("cli-batch", "plan");
    let cornell = test_data("gltf/bevy/CornellBox.glb");
    let lamp = test_data("gltf/kelvin/animated_lamp.gltf");
    let manifest = write_manifest(
        &dir,
        &format!(
            r#"{{"name": "a", "output": "out/same.exr", "size": "8x8", "spp": 1}},
               {{"name": "b", "output": "out/same.exr", "size": "8x8", "spp": 2}},
               {{"name": "tif", "output": "out/x.tif", "size": "8x8"}},
               {{"name": "vol", "bake": "volume", "scene": "{c}", "output": "out/v.exr"}},
               {{"name": "lamp", "scene": "{l}", "output": "out/lamp_##.exr", "frames": "1-5x2,8", "size": "8x8", "spp": 1}}"#,
            c = cornell.display(),
            l = lamp.display()
        ),
    );
    let plan = kelvin(&["batch", &manifest, "--plan"]);
    let plan: serde_json::Value = serde_json::from_slice(&plan.stdout).unwrap();
    let jobs = plan["jobs"].as_array().unwrap();
    let error = |k: usize| jobs[k]["error"].as_str().unwrap_or_default().to_owned();
    for k in [0, 1] {
        assert!(error(k).contains("same.exr: written by job 0 (a) and job 1 (b)"), "{}", error(k));
    }
    assert!(error(2).contains("x.tif: use .exr or .png"), "{}", error(2));
    assert!(error(3).contains("a volume is written as .ktx2"), "{}", error(3));
    let frames: Vec<u64> = jobs[4..].iter().map(|j| j["frame"].as_u64().unwrap()).collect();
    assert_eq!(frames, [1, 3, 5, 8]);
    let out = kelvin(&["batch", &manifest, "--task", "6"]);
    assert!(out.status.success(), "{}", text(&out));
    let written: Vec<_> = std::fs::read_dir(dir.join("out")).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(written.len(), 2, "only frame 5 and its preview: {written:?}");
    assert!(dir.join("out/lamp_05.exr").exists());
    let out = kelvin(&["batch", &manifest, "--task", "8"]);
    assert!(!out.status.success() && text(&out).contains("the plan has 8 entries"), "{}", text(&out));
    assert!(!kelvin(&["batch", &manifest, "--task", "0"]).status.success(), "a failed entry fails its task");
}

/// Outputs written twice are found frame by frame: a chunk that writes a frame another job writes
/// conflicts with it; many jobs writing one output are each refused with at most three writers
/// named (all named, the messages grew with the square of the jobs: 0.6 s and 48 MB of errors for
/// 488 chunk entries).
#[test]
fn outputs_written_twice_are_found_per_frame_and_named_briefly() {
    let dir = TempDir::new("cli-batch", "writers");
    let lamp = test_data("gltf/kelvin/animated_lamp.gltf");
    let mut jobs = vec![
        format!(
            r#"{{"name": "chunked", "scene": "{}", "output": "c_#.exr", "frames": "1-4", "chunk": 2, "size": "4x4"}}"#,
            lamp.display()
        ),
        r#"{"name": "three", "output": "c_3.exr", "size": "4x4"}"#.to_owned(),
    ];
    jobs.extend((0..50).map(|k| format!(r#"{{"name": "m{k}", "output": "many.exr", "size": "4x4"}}"#)));
    let manifest = write_manifest(&dir, &jobs.join(","));
    let plan: serde_json::Value = serde_json::from_slice(&kelvin(&["batch", &manifest, "--plan"]).stdout).unwrap();
    let jobs = plan["jobs"].as_array().unwrap();
    let error = |k: usize| jobs[k]["error"].as_str().unwrap_or_default().to_owned();
    assert!(jobs[0]["error"].is_null(), "frames 1-2 conflict with nothing: {}", jobs[0]);
    for k in [1, 2] {
        assert!(error(k).contains("c_3.exr: written by job 0 (chunked frames 3-4) and job 1 (three)"), "{}", error(k));
    }
    for k in 3..53 {
        assert!(
            error(k).ends_with("many.exr: written by job 2 (m0) and job 3 (m1) and job 4 (m2) and 47 more"),
            "{}",
            error(k)
        );
    }
}

/// `chunk` frames per entry, as farms chunk their tasks: each entry renders its frames in one
/// process, each frame's EXR byte for byte the one `kelvin render --frames K` writes alone; the
/// plan says a chunk does not tile, and a chunk is finished only when all its frames are. Two
/// chunks of one job share its output pattern but write different frames: not a conflict (the
/// fuzzer found them refused as "written by job 0 and job 0").
#[test]
fn chunks_of_frames_render_as_each_frame_alone() {
    let dir = TempDir::new("cli-batch", "chunks");
    let scene = test_data("gltf/kelvin/animated_lamp.gltf");
    let job = format!(
        r#"{{"name": "lamp", "scene": "{}", "output": "anim/f_##.exr", "frames": "1-11x2", "chunk": 3,
             "fps": 4, "size": "6x5", "spp": 2}}"#,
        scene.display()
    );
    let manifest = write_manifest(&dir, &job);
    let plan: serde_json::Value = serde_json::from_slice(&kelvin(&["batch", &manifest, "--plan"]).stdout).unwrap();
    let jobs = plan["jobs"].as_array().unwrap();
    let frames: Vec<&serde_json::Value> = jobs.iter().map(|j| &j["frames"]).collect();
    assert_eq!(frames, [&serde_json::json!([1, 3, 5]), &serde_json::json!([7, 9, 11])]);
    assert!(jobs.iter().all(|j| j["error"].is_null()), "{jobs:?}");
    assert_eq!(
        (jobs[0]["name"].as_str(), jobs[1]["name"].as_str()),
        (Some("lamp frames 1-5"), Some("lamp frames 7-11"))
    );
    assert!(jobs[0]["untileable"].as_str().unwrap().contains("chunk of 3 frames"), "{}", jobs[0]);
    let out = kelvin(&["batch", &manifest]);
    assert!(out.status.success() && text(&out).contains("2 jobs: 2 rendered"), "{}", text(&out));
    let scene = scene.to_str().unwrap();
    for k in [1, 3, 5, 7, 11] {
        let alone = dir.join(format!("alone_{k}.exr"));
        let args = ["render", scene, "--frames", &k.to_string(), "--fps", "4", "--size", "6x5", "--spp", "2"];
        assert!(kelvin(&[&args[..], &["-o", alone.to_str().unwrap()]].concat()).status.success());
        let chunked = std::fs::read(dir.join(format!("anim/f_{k:02}.exr"))).unwrap();
        assert!(chunked == std::fs::read(&alone).unwrap(), "frame {k} of a chunk differs from frame {k} alone");
    }
    std::fs::remove_file(dir.join("anim/f_03.exr")).unwrap();
    let plan: serde_json::Value = serde_json::from_slice(&kelvin(&["batch", &manifest, "--plan"]).stdout).unwrap();
    assert_eq!((plan["jobs"][0]["done"].as_bool(), plan["jobs"][1]["done"].as_bool()), (Some(false), Some(true)));
}

/// A finished bake is not finished once a file its scene references changes (the IES profile
/// here): `--plan` says so and names the file, and `batch` bakes it again.
#[test]
fn a_bake_whose_referenced_file_changed_is_not_finished() {
    let dir = TempDir::new("cli-batch", "bake-inputs");
    common::room_files::write(&dir.join(""));
    let manifest = write_manifest(
        &dir,
        r#"{"name": "maps", "bake": "lightmaps", "scene": "room.gltf", "output": "out/maps",
            "settings": {"size": 8, "spp": 1}}"#,
    );
    let plan = |m: &str| -> serde_json::Value {
        serde_json::from_slice::<serde_json::Value>(&kelvin(&["batch", m, "--plan"]).stdout).unwrap()["jobs"][0].clone()
    };
    let first = kelvin(&["batch", &manifest]);
    assert!(first.status.success(), "{}", text(&first));
    assert_eq!(plan(&manifest)["done"], true);
    common::room_files::change(&dir.join(""), "lamp.ies");
    let entry = plan(&manifest);
    assert_eq!(entry["done"], false, "{entry}");
    assert!(entry["stale"].as_str().unwrap().contains("/inputs/input lamp.ies"), "{entry}");
    let again = text(&kelvin(&["batch", &manifest]));
    assert!(again.contains("1 jobs: 1 rendered"), "{again}");
}

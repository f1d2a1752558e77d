//! Provenance where the farm meets it: every EXR records the program, the scene's SHA-256, the
//! settings, the frame and the tile; `kelvin merge` refuses tiles of different renders naming the
//! field; `kelvin batch` renders again an output that is not its job's (other settings, an
//! unreadable file) and removes temporaries a killed writer left.

mod common;

use std::process::{Command, Output};

use common::files::{TempDir, test_data};
use kelvin::render::film_io::read_exr_provenance;

fn kelvin(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_kelvin")).args(args).output().expect("kelvin runs")
}

fn text(out: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr))
}

#[test]
fn exrs_record_what_made_them_and_merge_checks_it() {
    let dir = TempDir::new("provenance", "merge");
    let cornell = test_data("gltf/bevy/CornellBox.glb");
    let c = cornell.to_str().unwrap();
    let out = |name: &str| dir.join(name).to_str().unwrap().to_owned();
    let base = ["render", c, "--size", "8x6", "--spp", "2"];
    let run = |extra: &[&str]| {
        let o = kelvin(&[&base[..], extra].concat());
        assert!(o.status.success(), "{}", text(&o));
    };
    run(&["-o", &out("full.exr")]);
    let p = read_exr_provenance(&dir.join("full.exr")).unwrap();
    assert_eq!(p.0["scene"], kelvin::provenance::file_sha256(&cornell).unwrap());
    assert_eq!(p.0["version"], env!("CARGO_PKG_VERSION"));
    assert!(p.0["program"].starts_with("kelvin sha256:"), "{}", p.0["program"]);
    assert!(p.0["settings"].contains("spp: 2") && p.0["settings"].contains("width: 8"), "{}", p.0["settings"]);
    assert!(!p.0.contains_key("tile") && !p.0.contains_key("frame"));
    run(&["--crop", "0,0,4,6", "-o", &out("a.exr")]);
    run(&["--crop", "4,0,8,6", "-o", &out("b.exr")]);
    assert_eq!(read_exr_provenance(&dir.join("a.exr")).unwrap().0["tile"], "0,0,4,6");
    let merged = kelvin(&["merge", &out("a.exr"), &out("b.exr"), "-o", &out("merged.exr")]);
    assert!(merged.status.success(), "{}", text(&merged));
    let same = std::fs::read(dir.join("merged.exr")).unwrap() == std::fs::read(dir.join("full.exr")).unwrap();
    assert!(same, "the merged image, provenance included, is the full render's bytes");
    // A tile of another seed has the same size and window but is another render.
    run(&["--crop", "4,0,8,6", "--seed", "1", "-o", &out("b1.exr")]);
    let refused = kelvin(&["merge", &out("a.exr"), &out("b1.exr"), "-o", &out("bad.exr")]);
    let log = text(&refused);
    assert!(!refused.status.success() && log.contains("b1.exr: its settings is") && log.contains("seed: 1"), "{log}");
    assert!(!dir.join("bad.exr").exists());
}

#[test]
fn batch_renders_again_what_is_not_its_jobs_and_clears_stale_temporaries() {
    let dir = TempDir::new("provenance", "batch");
    let manifest = dir.join("jobs.json");
    let write = |spp: u32| {
        let jobs =
            format!(r#"{{"jobs": [{{"name": "room", "output": "out/room.exr", "size": "8x8", "spp": {spp}}}]}}"#);
        std::fs::write(&manifest, jobs).unwrap();
    };
    let m = manifest.to_str().unwrap();
    write(2);
    assert!(kelvin(&["batch", m]).status.success());
    let again = text(&kelvin(&["batch", m]));
    assert!(again.contains("1 jobs: 0 rendered, 1 skipped"), "{again}");
    // Other settings: the existing file is not this job's.
    write(3);
    let plan: serde_json::Value = serde_json::from_slice(&kelvin(&["batch", m, "--plan"]).stdout).unwrap();
    assert_eq!(plan["jobs"][0]["done"], false);
    assert!(plan["jobs"][0]["stale"].as_str().unwrap().contains("settings"), "{}", plan["jobs"][0]);
    let log = text(&kelvin(&["batch", m]));
    assert!(log.contains("not this job's output") && log.contains("1 jobs: 1 rendered"), "{log}");
    // A file that does not read back (cut short by something other than kelvin) is rendered again.
    let room = dir.join("out/room.exr");
    let bytes = std::fs::read(&room).unwrap();
    std::fs::write(&room, &bytes[..bytes.len() / 2]).unwrap();
    let plan: serde_json::Value = serde_json::from_slice(&kelvin(&["batch", m, "--plan"]).stdout).unwrap();
    assert!(plan["jobs"][0]["stale"].as_str().unwrap().contains("does not read back"), "{}", plan["jobs"][0]);
    // Temporaries are named `.<name>.<host>.<pid>.<random>.partial`. One of a killed writer on this
    // host (its process gone) is removed, a live writer's is kept; another host's (storage shared
    // between machines) is kept while it is recent, however its process id reads here, and removed
    // once untouched for an hour.
    let host = kelvin::render::partial::this_host();
    let temp =
        |name: &str, host: &str, pid: u32| dir.join(format!("out/.{name}.{host}.{pid}.0123456789abcdef.partial"));
    let stale = temp("room.exr", host, 4_000_000);
    let live = temp("room.png", host, std::process::id());
    let elsewhere = temp("room.exr", "render-node-7", 4_000_000);
    let abandoned = temp("room.png", "render-node-7", std::process::id());
    for file in [&stale, &live, &elsewhere, &abandoned] {
        std::fs::write(file, b"half").unwrap();
    }
    let two_hours_ago = std::time::SystemTime::now() - std::time::Duration::from_secs(7200);
    std::fs::File::options().write(true).open(&abandoned).unwrap().set_modified(two_hours_ago).unwrap();
    let log = text(&kelvin(&["batch", m]));
    assert!(log.contains("1 jobs: 1 rendered"), "{log}");
    assert!(!stale.exists() && live.exists(), "{log}");
    assert!(elsewhere.exists() && !abandoned.exists(), "{log}");
    assert!(std::fs::read(&room).unwrap().len() > bytes.len() / 2);
}

/// `kelvin batch --plan`'s first entry for the manifest `m`.
fn planned(m: &str) -> serde_json::Value {
    let out = kelvin(&["batch", m, "--plan"]);
    assert!(out.status.success(), "{}", text(&out));
    serde_json::from_slice::<serde_json::Value>(&out.stdout).unwrap()["jobs"][0].clone()
}

#[test]
fn a_changed_buffer_texture_ies_or_env_map_unfinishes_the_output_and_merge_refuses_its_tiles() {
    use common::room_files;
    let dir = TempDir::new("provenance", "inputs");
    let scene = room_files::write(&dir.join(""));
    let manifest = dir.join("jobs.json");
    let job = r#"{"jobs": [{"scene": "room.gltf", "output": "out/room.exr", "size": "8x8", "spp": 1,
                 "settings": {"env": "env.hdr"}}]}"#;
    std::fs::write(&manifest, job).unwrap();
    let m = manifest.to_str().unwrap();
    let first = kelvin(&["batch", m]);
    assert!(first.status.success(), "{}", text(&first));
    // Every file the render read is recorded, with the digest of its bytes.
    let p = read_exr_provenance(&dir.join("out/room.exr")).unwrap();
    for (key, file) in [("input box.bin", "box.bin"), ("input tex.png", "tex.png"), ("input lamp.ies", "lamp.ies")]
        .into_iter()
        .chain([("env", "env.hdr"), ("scene", "room.gltf")])
    {
        let digest = kelvin::provenance::file_sha256(&dir.join(file)).unwrap();
        assert_eq!(p.0.get(key), Some(&digest), "{key} in {:?}", p.0);
    }
    // The driver checks each node holds the referenced files too.
    let inputs = planned(m)["inputs"].clone();
    for file in room_files::FILES.iter().chain(&["room.gltf"]) {
        assert!(inputs.as_object().unwrap().keys().any(|k| k.ends_with(file)), "{file} not in {inputs}");
    }
    assert_eq!(planned(m)["done"], true);
    for name in room_files::FILES {
        let original = std::fs::read(dir.join(name)).unwrap();
        room_files::change(&dir.join(""), name);
        let entry = planned(m);
        assert_eq!(entry["done"], false, "{name} changed, yet the output is finished: {entry}");
        let key = if name == "env.hdr" { "its env is".to_owned() } else { format!("its input {name} is") };
        assert!(entry["stale"].as_str().unwrap_or_default().contains(&key), "{name}: {entry}");
        std::fs::write(dir.join(name), original).unwrap();
        assert_eq!(planned(m)["done"], true, "{name} restored");
    }
    // Tiles of two geometries (the lamp's vertices in box.bin moved between them) do not merge.
    let s = scene.to_str().unwrap();
    let tile = |crop: &str, out: &str| {
        let o = kelvin(&["render", s, "--size", "8x8", "--spp", "1", "--crop", crop, "-o", out]);
        assert!(o.status.success(), "{}", text(&o));
    };
    let (a, b) = (dir.join("a.exr"), dir.join("b.exr"));
    tile("0,0,4,8", a.to_str().unwrap());
    room_files::change(&dir.join(""), "box.bin");
    tile("4,0,8,8", b.to_str().unwrap());
    let merged =
        kelvin(&["merge", a.to_str().unwrap(), b.to_str().unwrap(), "-o", dir.join("m.exr").to_str().unwrap()]);
    let log = text(&merged);
    assert!(!merged.status.success() && log.contains("its input box.bin is"), "{log}");
}

#[test]
fn a_scene_replaced_mid_render_records_the_digest_of_the_file_it_read() {
    use std::io::BufRead;
    let dir = TempDir::new("provenance", "replaced");
    let scene = common::room_files::write(&dir.join(""));
    let read = kelvin::provenance::file_sha256(&scene).unwrap();
    let out = dir.join("room.exr");
    let mut child = Command::new(env!("CARGO_BIN_EXE_kelvin"))
        .args(["render", scene.to_str().unwrap(), "--size", "16x16", "--spp", "1", "--time", "1.5"])
        .args(["-o", out.to_str().unwrap()])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // The loader's summary says the scene was read; then another file takes its name.
    let mut log = String::new();
    let mut lines = std::io::BufReader::new(child.stderr.take().unwrap()).lines();
    for line in lines.by_ref() {
        let line = line.unwrap();
        log += &line;
        if line.starts_with("scene ") {
            break;
        }
    }
    let text = std::fs::read_to_string(&scene).unwrap().replace("\"floor\"", "\"other floor\"");
    std::fs::write(dir.join("next.gltf"), text).unwrap();
    std::fs::rename(dir.join("next.gltf"), &scene).unwrap();
    log.extend(lines.map(|l| l.unwrap()));
    assert!(child.wait().unwrap().success(), "{log}");
    let recorded = read_exr_provenance(&out).unwrap();
    assert_ne!(read, kelvin::provenance::file_sha256(&scene).unwrap(), "the scene was replaced");
    assert_eq!(recorded.0["scene"], read, "the image shows the scene read, not its replacement");
}

#[test]
fn a_png_of_other_settings_is_not_finished() {
    let dir = TempDir::new("provenance", "png");
    let manifest = dir.join("jobs.json");
    let write = |settings: &str| {
        let job = format!(r#"{{"jobs": [{{"output": "out/a.png", "size": "8x8", {settings}}}]}}"#);
        std::fs::write(&manifest, job).unwrap();
    };
    let m = manifest.to_str().unwrap();
    write(r#""spp": 1"#);
    let first = kelvin(&["batch", m]);
    assert!(first.status.success(), "{}", text(&first));
    assert_eq!(planned(m)["done"], true);
    write(r#""spp": 2"#);
    let entry = planned(m);
    assert_eq!(entry["done"], false, "{entry}");
    assert!(entry["stale"].as_str().unwrap().contains("its settings is"), "{entry}");
    // The exposure changes a PNG's pixels (an EXR's not).
    write(r#""spp": 1, "settings": {"exposure": 1.5}"#);
    let entry = planned(m);
    assert_eq!(entry["done"], false, "{entry}");
    assert!(entry["stale"].as_str().unwrap().contains("its exposure is auto"), "{entry}");
}

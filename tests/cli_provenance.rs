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
    // A killed writer's temporary (its process gone) is removed; a live one's is kept.
    let stale = dir.join("out/.room.exr.4000000.partial");
    let live = dir.join(format!("out/.room.png.{}.partial", std::process::id()));
    std::fs::write(&stale, b"half").unwrap();
    std::fs::write(&live, b"half").unwrap();
    let log = text(&kelvin(&["batch", m]));
    assert!(log.contains("1 jobs: 1 rendered"), "{log}");
    assert!(!stale.exists() && live.exists(), "{log}");
    assert!(std::fs::read(&room).unwrap().len() > bytes.len() / 2);
}

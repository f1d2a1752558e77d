//! `kelvin render`: the --report summary line, the time of each pass and the light system's run
//! report; crops and merges; the sky; errors of bad crops and frame requests.

use std::process::Command;

#[test]
fn report_prints_summary_passes_and_run_report() {
    let dir = std::env::temp_dir().join(format!("kelvin-cli-render-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("report.png");
    let output = Command::new(env!("CARGO_BIN_EXE_kelvin"))
        .args(["render", "-o", out.to_str().unwrap(), "--size", "16x12", "--spp", "1", "--report"])
        .output()
        .expect("kelvin runs");
    let (stdout, stderr) = (String::from_utf8_lossy(&output.stdout), String::from_utf8_lossy(&output.stderr));
    assert!(output.status.success(), "{stderr}");
    assert!(stdout.contains("rendered 16x12 at 1 spp") && stdout.contains("M samples/s"), "{stdout}");
    assert!(stdout.contains("passes: camera") && stdout.contains("light system"), "{stdout}");
    assert!(stderr.contains("light_sampler"), "the run report names the systems that ran: {stderr}");
    assert!(std::fs::metadata(&out).unwrap().len() > 100);
    std::fs::remove_dir_all(&dir).ok();
}

/// An emissive glTF mesh of one good and one degenerate (collinear) triangle.
fn write_degenerate_emitter(path: &std::path::Path) {
    use base64::Engine;
    let positions: [[f32; 3]; 6] =
        [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]];
    let bin: Vec<u8> = positions.iter().flatten().flat_map(|c| c.to_le_bytes()).collect();
    let uri =
        format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(&bin));
    let json = serde_json::json!({
        "asset": { "version": "2.0" },
        "scene": 0, "scenes": [{ "nodes": [0] }], "nodes": [{ "mesh": 0 }],
        "meshes": [{ "name": "panel", "primitives": [{ "attributes": { "POSITION": 0 }, "material": 0 }] }],
        "materials": [{ "emissiveFactor": [1.0, 1.0, 1.0] }],
        "accessors": [{ "bufferView": 0, "componentType": 5126, "count": 6, "type": "VEC3",
                        "min": [0.0, 0.0, 0.0], "max": [2.0, 1.0, 0.0] }],
        "bufferViews": [{ "buffer": 0, "byteLength": bin.len() }],
        "buffers": [{ "byteLength": bin.len(), "uri": uri }],
    });
    std::fs::write(path, serde_json::to_vec(&json).unwrap()).unwrap();
}

/// A light the render's first update rejects in part (an emissive mesh's degenerate triangle) is
/// still in the report after the last batch, and the report's counts cover every batch.
#[test]
fn report_covers_every_batch_of_the_render() {
    let dir = std::env::temp_dir().join(format!("kelvin-cli-render-batches-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("panel.gltf");
    write_degenerate_emitter(&scene);
    let out = dir.join("report.png");
    // 96 x 96 x 4 = 36864 camera samples: three batches of the light system (one update each
    // with direct lighting; the path tracer adds one per bounce).
    let output = Command::new(env!("CARGO_BIN_EXE_kelvin"))
        .args(["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "--size", "96x96", "--spp", "4"])
        .args(["--report", "--integrator", "direct"])
        .output()
        .expect("kelvin runs");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    assert!(stderr.contains("warning: area light") && stderr.contains("1 degenerate triangles skipped"), "{stderr}");
    assert!(stderr.contains("36864 points"), "points summed over batches: {stderr}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn light_sampler_defaults_to_the_light_bvh() {
    let output = Command::new(env!("CARGO_BIN_EXE_kelvin")).args(["render", "--help"]).output().expect("kelvin runs");
    let help = String::from_utf8_lossy(&output.stdout);
    // The option's block: its lines up to the next option.
    let mut lines = help.lines().skip_while(|l| !l.trim_start().starts_with("--light-sampler"));
    let first = lines.next().unwrap_or_default();
    let block: Vec<&str> = lines.take_while(|l| !l.trim_start().starts_with("--")).collect();
    assert!(first.contains("--light-sampler") && block.join("\n").contains("[default: bvh]"), "{help}");
}

/// `--sky`: a real glTF scene under a physical sun and sky, in both colour modes; night is black
/// and bad specs are clear errors.
#[test]
fn sky_lights_a_gltf_scene_through_the_cli() {
    let dir = std::env::temp_dir().join(format!("kelvin-cli-sky-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/gltf/bench/env_objects.glb");
    assert!(scene.exists(), "missing test data {}", scene.display());
    let render = |name: &str, sky: &str, color: &str| {
        let out = dir.join(name);
        let output = Command::new(env!("CARGO_BIN_EXE_kelvin"))
            .args(["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "--size", "32x24", "--spp", "4"])
            .args(["--sky", sky, "--color", color])
            .output()
            .expect("kelvin runs");
        (output, out)
    };
    let mean_luminance = |path: &std::path::Path| {
        let img = kelvin::scene::image::load_image(path).unwrap().image;
        img.pixels.iter().map(|p| kelvin::scene::image::LUMINANCE_WEIGHTS.dot(*p) as f64).sum::<f64>()
            / img.pixels.len() as f64
    };
    let mut day = [0.0; 2];
    for (k, color) in ["rgb", "spectral"].into_iter().enumerate() {
        let (output, out) = render(&format!("day_{color}.exr"), "48.86,2.35,2024-06-21T10:00,3", color);
        assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
        day[k] = mean_luminance(&out);
        // Daylight: the scene's surfaces and the visible sky are thousands of nit.
        assert!(day[k] > 500.0 && day[k].is_finite(), "{color}: mean luminance {}", day[k]);
    }
    assert!((day[0] / day[1] - 1.0).abs() < 0.15, "RGB {} vs spectral {}", day[0], day[1]);
    let (output, night) = render("night.exr", "48.86,2.35,2024-06-21T23:30", "rgb");
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    assert!(mean_luminance(&night) < 1e-3 * day[0], "night is {}", mean_luminance(&night));
    for (bad, says) in [
        ("91,0,2024-06-21T12:00", "latitude"),
        ("48,2,2024-06-21", "date-time"),
        ("48,2,2024-06-31T12:00", "day 31"),
        ("48,2,2024-06-21T12:00,11", "turbidity"),
        ("48,two,2024-06-21T12:00", "longitude"),
        ("nan,2,2024-06-21T12:00", "latitude"),
    ] {
        let (output, _) = render("bad.exr", bad, "rgb");
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(!output.status.success() && stderr.contains(says) && !stderr.contains("panicked"), "{bad}: {stderr}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

fn kelvin(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_kelvin")).args(args).output().expect("kelvin runs")
}

/// Tiles rendered with `--crop` (edges aligned to nothing) and joined by `kelvin merge` give the
/// plain render's EXR byte for byte, in RGB and spectral modes; each tile EXR holds exactly its
/// region of the full image.
#[test]
fn cropped_tiles_merge_into_the_full_render_byte_for_byte() {
    let dir = std::env::temp_dir().join(format!("kelvin-cli-crop-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = |name: &str| dir.join(name).to_str().unwrap().to_owned();
    for color in ["rgb", "spectral"] {
        let common = ["--size", "41x27", "--spp", "3", "--seed", "5", "--color", color];
        let full = path(&format!("full-{color}.exr"));
        let out = kelvin(&[&["render", "-o", &full][..], &common].concat());
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let crops = ["0,0,41,9", "0,9,17,27", "17,9,41,27"];
        let mut tiles = Vec::new();
        for (i, crop) in crops.iter().enumerate() {
            let tile = path(&format!("tile{i}-{color}.exr"));
            let out = kelvin(&[&["render", "-o", &tile, "--crop", crop][..], &common].concat());
            assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
            tiles.push(tile);
        }
        let (_, _, full_px) = kelvin::render::film_io::read_exr(std::path::Path::new(&full)).unwrap();
        let tile = kelvin::render::film_io::read_exr_tile(std::path::Path::new(&tiles[2])).unwrap();
        assert_eq!((tile.width, tile.height, tile.crop.to_string()), (41, 27, "17,9,41,27".into()));
        let rows = (9..27).flat_map(|y| full_px[y * 41 + 17..y * 41 + 41].to_vec()).collect::<Vec<_>>();
        assert!(tile.pixels == rows, "{color}: the tile holds its region of the full render");

        let merged = path(&format!("merged-{color}.exr"));
        let out =
            kelvin(&[&["merge", "-o", &merged][..], &tiles.iter().map(String::as_str).collect::<Vec<_>>()].concat());
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        assert!(std::fs::read(&merged).unwrap() == std::fs::read(&full).unwrap(), "{color}: merged EXR differs");
    }
    // A missing tile is a gap, a tile given twice an overlap; both name what is wrong.
    let merged = path("bad.exr");
    let (t0, t1) = (path("tile0-rgb.exr"), path("tile1-rgb.exr"));
    let out = kelvin(&["merge", "-o", &merged, &t0, &t1]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("in no tile") && err.contains("17,9,41,27"), "{err}");
    let out = kelvin(&["merge", "-o", &merged, &t0, &t1, &t1]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("overlap") && err.contains("tile1-rgb.exr"), "{err}");
    assert!(!std::path::Path::new(&merged).exists());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_crops_are_clear_errors() {
    for (crop, says) in [
        ("5,5,5,9", "is empty"),
        ("8,2,3,9", "is empty"),
        ("0,0,50,9", "not inside the 40x30 image"),
        ("1,2,3", "expected four whole numbers"),
    ] {
        let out = kelvin(&["render", "--size", "40x30", "--crop", crop, "-o", "never-written.exr"]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && err.contains(says) && !err.contains("panicked"), "{crop}: {err}");
    }
    let out = kelvin(&["render", "--size", "40x30", "--crop", "0,0,4,4", "-o", "tile.png"]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("written as .exr"));
    // Tiles that would not be regions of the full render are refused before the scene loads.
    let tile = ["render", "--size", "40x30", "--crop", "0,0,4,4", "-o", "never-written.exr"];
    for (extra, says) in [(&["--light-sampler", "restir"][..], "ReSTIR"), (&["--time", "1"][..], "time budget")] {
        let out = kelvin(&[&tile[..], extra].concat());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && err.contains("--crop 0,0,4,4") && err.contains(says), "{extra:?}: {err}");
    }
    // A crop of the whole image is the whole render, ReSTIR included.
    let dir = std::env::temp_dir().join(format!("kelvin-cli-restir-crop-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (full, tile) = (dir.join("full.exr"), dir.join("tile.exr"));
    let restir = ["--size", "12x9", "--spp", "2", "--light-sampler", "restir"];
    let out = kelvin(&[&["render", "-o", full.to_str().unwrap()][..], &restir].concat());
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let out = kelvin(&[&["render", "-o", tile.to_str().unwrap(), "--crop", "0,0,12,9"][..], &restir].concat());
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let (_, _, a) = kelvin::render::film_io::read_exr(&full).unwrap();
    assert!(a == kelvin::render::film_io::read_exr_tile(&tile).unwrap().pixels);
    std::fs::remove_dir_all(&dir).ok();
}

/// `--frames` names what is wrong: a still scene, an animation the file lacks, several frames
/// into one file, a bad range or rate.
#[test]
fn bad_frame_requests_are_clear_errors() {
    let lamp = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/gltf/kelvin/animated_lamp.gltf");
    let cornell = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/gltf/bevy/CornellBox.glb");
    for (args, says) in [
        (vec![cornell, "--frames", "0..2", "-o", "never_#.exr"], "has no animation"),
        (vec![lamp, "--frames", "0..2", "--animation", "night", "-o", "never_#.exr"], "(it has 0: day)"),
        (vec![lamp, "--frames", "0..2", "--animation", "1", "-o", "never_#.exr"], "--animation 1: not in"),
        (vec![lamp, "--frames", "0..2", "-o", "never.exr"], "needs a run of '#'"),
        (vec![lamp, "--frames", "2..0", "-o", "never_#.exr"], "0 is before 2"),
        (vec![lamp, "--frames", "1-9x0", "-o", "never_#.exr"], "a step of 0"),
        (vec![lamp, "--frames", "0..2", "--fps", "0", "-o", "never_#.exr"], "frames per second"),
    ] {
        let out = kelvin(&[&["render", "--size", "4x4", "--spp", "1"][..], &args].concat());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && err.contains(says) && !err.contains("panicked"), "{args:?}: {err}");
    }
    assert!(!std::path::Path::new("never_0.exr").exists());
}

/// `--light-sampler restir`: the renderer's camera batches carry their image layout, so spatial
/// reuse runs (the report says so, with M and k), and the image's mean matches RIS's (both
/// unbiased; the default scene, direct lighting). `--biased-reuse` runs too.
#[test]
fn restir_reuses_neighbours_in_a_render() {
    let dir = std::env::temp_dir().join(format!("kelvin-cli-restir-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mean = |sampler: &[&str]| {
        let out = dir.join(format!("{}.exr", sampler.join("")));
        let mut args = vec!["render", "-o", out.to_str().unwrap(), "--size", "64x48", "--spp", "16", "--report"];
        args.extend(["--integrator", "direct", "--light-sampler"]);
        args.extend(sampler);
        let output = kelvin(&args);
        let stderr = String::from_utf8_lossy(&output.stderr).to_string();
        assert!(output.status.success(), "{stderr}");
        let (_, _, pixels) = kelvin::render::film_io::read_exr(&out).unwrap();
        (pixels.iter().map(|p| (p.x + p.y + p.z) as f64).sum::<f64>() / pixels.len() as f64, stderr)
    };
    let (ris, _) = mean(&["ris"]);
    let (restir, report) = mean(&["restir", "--neighbours", "4", "--radius", "8"]);
    assert!(report.contains("ReSTIR: RIS M=8; temporal off; spatial: k=4 within 8 px"), "{report}");
    let (biased, report) = mean(&["restir", "--biased-reuse"]);
    assert!(report.contains("biased 1/sum M"), "{report}");
    eprintln!("image mean: RIS {ris:.4}, ReSTIR {restir:.4}, biased {biased:.4}");
    assert!(ris > 0.0 && (restir / ris - 1.0).abs() < 0.05, "ReSTIR {restir} vs RIS {ris}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Options the light choice would ignore are refused before any work, naming both sides:
/// `--all-lights` with a resampling sampler (which it used to override, then tile as ReSTIR),
/// resampling options under a sampler that does not resample, reuse options without ReSTIR.
/// The same job written in a manifest is refused by `kelvin batch` with the same words.
#[test]
fn contradictory_light_options_are_refused() {
    let dir = std::env::temp_dir().join(format!("kelvin-cli-contradictions-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("never.exr");
    let o = out.to_str().unwrap();
    let cases: &[(&[&str], &[&str])] = &[
        (&["--all-lights", "--light-sampler", "ris"], &["all_lights", "ris"]),
        (&["--all-lights", "--light-sampler", "restir"], &["all_lights", "restir"]),
        (&["--light-sampler", "uniform", "--candidates", "4"], &["candidates = 4", "uniform"]),
        (&["--candidates", "4"], &["candidates = 4", "bvh"]),
        (&["--light-sampler", "ris", "--neighbours", "2"], &["neighbours = 2", "ris"]),
        (&["--light-sampler", "power", "--radius", "3"], &["radius = 3", "power"]),
        (&["--biased-reuse"], &["biased_reuse", "bvh"]),
    ];
    for (args, words) in cases {
        let run = kelvin(&[&["render", "-o", o, "--size", "8x8", "--spp", "1"], *args].concat());
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert!(!run.status.success(), "{args:?} was accepted");
        assert!(words.iter().all(|w| stderr.contains(w)), "{args:?}: {stderr}");
    }
    assert!(!out.exists(), "a refused render wrote its output");
    // Each is accepted alone, and with the sampler it belongs to.
    for args in [
        &["--all-lights"][..],
        &["--light-sampler", "ris", "--candidates", "4"],
        &["--light-sampler", "restir", "--candidates", "2", "--neighbours", "2", "--radius", "3", "--biased-reuse"],
    ] {
        let run = kelvin(&[&["render", "-o", o, "--size", "8x8", "--spp", "1"], args].concat());
        assert!(run.status.success(), "{args:?}: {}", String::from_utf8_lossy(&run.stderr));
    }
    let manifest = dir.join("jobs.json");
    let job = r#"{"jobs": [{"name": "both", "output": "both.exr", "size": "8x8", "spp": 1,
                  "settings": {"all_lights": true, "light_sampler": "restir"}}]}"#;
    std::fs::write(&manifest, job).unwrap();
    let run = kelvin(&["batch", manifest.to_str().unwrap()]);
    let log = format!("{}{}", String::from_utf8_lossy(&run.stdout), String::from_utf8_lossy(&run.stderr));
    assert!(!run.status.success() && log.contains("all_lights") && log.contains("restir"), "{log}");
    assert!(!dir.join("both.exr").exists());
    std::fs::remove_dir_all(&dir).ok();
}

/// `kelvin render` of the default scene into `out` (64x64, 1 spp), run by `sh` with a file size
/// limit of `limit_blocks` 512-byte blocks when given, SIGXFSZ ignored (so a write past it fails
/// with EFBIG, as one on a full disk fails with ENOSPC, instead of killing kelvin).
fn render_limited(out: &std::path::Path, scene: Option<&str>, limit_blocks: Option<u32>) -> std::process::Output {
    let limit = limit_blocks.map_or(String::new(), |b| format!("ulimit -f {b}; "));
    let script = format!("trap '' XFSZ; {limit}exec \"$@\"");
    let mut args = vec!["render".to_owned()];
    args.extend(scene.map(str::to_owned));
    args.extend(["--size", "64x64", "--spp", "1", "-o", out.to_str().unwrap()].map(str::to_owned));
    Command::new("sh")
        .args(["-c", &script, "sh", env!("CARGO_BIN_EXE_kelvin")])
        .args(args)
        .output()
        .expect("sh runs kelvin")
}

#[test]
fn exit_codes_say_a_full_disk_is_the_machines_and_a_missing_scene_the_inputs() {
    let dir = std::env::temp_dir().join(format!("kelvin-cli-render-exit-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let full = render_limited(&dir.join("full.exr"), None, Some(8));
    let log = String::from_utf8_lossy(&full.stderr);
    assert_eq!(full.status.code(), Some(3), "a full disk is an environment failure: {log}");
    assert!(log.contains("cannot write"), "{log}");
    assert!(!dir.join("full.exr").exists(), "no partial output under the output's name");
    let bad = render_limited(&dir.join("bad.exr"), Some(dir.join("missing.gltf").to_str().unwrap()), None);
    let log = String::from_utf8_lossy(&bad.stderr);
    assert_eq!(bad.status.code(), Some(2), "a missing scene is bad input: {log}");
    assert!(log.contains("missing.gltf"), "{log}");
    let fine = render_limited(&dir.join("fine.exr"), None, None);
    assert!(fine.status.success(), "{}", String::from_utf8_lossy(&fine.stderr));
    let help = Command::new(env!("CARGO_BIN_EXE_kelvin")).arg("--help").output().unwrap();
    let help = String::from_utf8_lossy(&help.stdout);
    assert!(help.contains("Exit codes:") && help.contains("3 environment or I/O"), "{help}");
    std::fs::remove_dir_all(&dir).ok();
}

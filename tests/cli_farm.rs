//! kelvin as a Deadline or OpenCue job script runs it: a task names its job and frames
//! (`kelvin batch M --job NAME --frames 11-15`) and does the same work when the manifest gains
//! jobs, skipping frames a killed attempt finished; farm frame lists (negative frames) reach the
//! task; its log file, created with its folder, has progress lines a monitor can tail; `render
//! --frames` creates its output folders; `render --log` logs its start, progress and outcome.

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

/// The manifest `jobs`, written to `dir/jobs.json`.
fn write_manifest(dir: &TempDir, jobs: &[String]) -> String {
    let path = dir.join("jobs.json");
    std::fs::write(&path, format!("{{\"jobs\": [{}]}}", jobs.join(","))).unwrap();
    path.to_str().unwrap().to_owned()
}

/// The files in `dir`, sorted.
fn files(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    names.sort();
    names
}

#[test]
fn a_frame_task_names_its_job_and_frames_and_keeps_them_when_the_manifest_grows() {
    let dir = TempDir::new("cli-farm", "task");
    let lamp = test_data("gltf/kelvin/animated_lamp.gltf");
    let job = |name: &str, output: &str, frames: &str| {
        format!(
            r#"{{"name": "{name}", "scene": "{}", "output": "{output}", "frames": "{frames}", "chunk": 2, "fps": 4,
                 "size": "6x5", "spp": 1}}"#,
            lamp.display()
        )
    };
    let lamp_job = job("lamp", "anim/f_##.exr", "1-6");
    let m = write_manifest(&dir, std::slice::from_ref(&lamp_job));
    // The manifest's only job needs no --job; the frames render in one process, each as it renders alone.
    let log = dir.join("logs/tasks/lamp-3.log");
    let out = kelvin(&["batch", &m, "--frames", "3-4", "--log", log.to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out));
    assert_eq!(files(&dir.join("anim")), ["f_03.exr", "f_03.png", "f_04.exr", "f_04.png"]);
    let alone = dir.join("alone_#.exr");
    let args = ["render", lamp.to_str().unwrap(), "--frames", "4", "--fps", "4", "--size", "6x5", "--spp", "1"];
    assert!(kelvin(&[&args[..], &["-o", alone.to_str().unwrap()]].concat()).status.success());
    assert!(std::fs::read(dir.join("anim/f_04.exr")).unwrap() == std::fs::read(dir.join("alone_4.exr")).unwrap());

    // The log: UTC-stamped lines, progress to 100%, the outcome; the same lines on stderr (not a terminal).
    let lines = std::fs::read_to_string(&log).unwrap();
    assert!(lines.lines().all(|l| l.len() > 21 && &l[4..5] == "-" && &l[19..21] == "Z "), "{lines}");
    assert!(lines.contains("progress 100%: [1/1] lamp frames 3-4 100%"), "{lines}");
    assert!(lines.contains("[1/1] lamp frames 3-4: rendered in"), "{lines}");
    assert!(String::from_utf8_lossy(&out.stderr).contains("progress 100%"), "{}", text(&out));

    // Jobs added before and after: the task names the same work. A task of frames 3-8 whose frames
    // 3 and 4 a killed attempt finished renders 5 and 6, the job's others (its range spans frames the
    // job lacks, as Deadline's <STARTFRAME>-<ENDFRAME> of a stepped job does), and appends to its log.
    let before = std::fs::metadata(dir.join("anim/f_03.exr")).unwrap().modified().unwrap();
    let grown = [
        r#"{"name": "still", "output": "still.exr", "size": "4x4", "spp": 1}"#.to_owned(),
        job("other", "other/o_##.exr", "1-6"),
        lamp_job,
        job("pre", "pre/p_##.exr", "-3--1"),
    ];
    let m = write_manifest(&dir, &grown);
    let out = kelvin(&["batch", &m, "--job", "lamp", "--frames", "3-8", "--log", log.to_str().unwrap()]);
    let said = text(&out);
    assert!(out.status.success(), "{said}");
    assert!(said.contains("frames 3,4 are finished already") && said.contains("lamp frames 5-6: rendered"), "{said}");
    assert!(said.contains("--frames: 2 frames, 7 to 8, not the job's, left out"), "{said}");
    assert_eq!(std::fs::metadata(dir.join("anim/f_03.exr")).unwrap().modified().unwrap(), before);
    assert!(dir.join("anim/f_06.exr").exists() && !dir.join("still.exr").exists() && !dir.join("other").exists());
    assert_eq!(std::fs::read_to_string(&log).unwrap().matches("kelvin batch").count(), 2, "appended");
    // Negative frames, as OpenCue and Deadline number pre-roll, in the task's frame list too.
    let out = kelvin(&["batch", &m, "--job", "pre", "--frames", "-2--1"]);
    assert!(out.status.success(), "{}", text(&out));
    assert_eq!(files(&dir.join("pre")), ["p_-1.exr", "p_-1.png", "p_-2.exr", "p_-2.png"]);

    // A task that names what is not there fails as bad input (exit 2), saying what and where.
    for (args, says) in [
        (
            &["--job", "lamp", "--frames", "7-9"][..],
            "job 2 (lamp): --frames: none of its frames is among the job's frames 1-6",
        ),
        (&["--job", "lamp", "--frames", "1-6y0"], "step of 0"),
        (&["--job", "lamp", "--frames", "1-6:2"], "1-6:2 is OpenCue's interleave"),
        (&["--job", "nope"], "--job nope: no job is named so (the jobs: still, other, lamp, pre)"),
        (&["--frames", "3"], "--frames needs --job NAME: the manifest has 4 jobs"),
        (&["--job", "still", "--frames", "3"], "job 0 (still): --frames: the job has no frames"),
    ] {
        let out = kelvin(&[&["batch", m.as_str()][..], args].concat());
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", text(&out));
        assert!(text(&out).contains(says), "{args:?}: expected '{says}' in {}", text(&out));
    }
}

#[test]
fn render_frames_creates_the_output_folders() {
    let dir = TempDir::new("cli-farm", "folders");
    let lamp = test_data("gltf/kelvin/animated_lamp.gltf");
    let pattern = dir.join("new/deeper/f_#.exr");
    let args = ["render", lamp.to_str().unwrap(), "--frames", "1-2", "--size", "6x5", "--spp", "1", "-o"];
    let out = kelvin(&[&args[..], &[pattern.to_str().unwrap()]].concat());
    assert!(out.status.success(), "{}", text(&out));
    assert_eq!(files(&dir.join("new/deeper")), ["f_1.exr", "f_1.png", "f_2.exr", "f_2.png"]);
    // A folder that cannot be made fails before any frame is rendered, naming the output.
    let blocked = dir.join("file");
    std::fs::write(&blocked, b"").unwrap();
    let out = kelvin(&[&args[..], &[blocked.join("f_#.exr").to_str().unwrap()]].concat());
    assert!(!out.status.success() && text(&out).contains("cannot create its folder"), "{}", text(&out));
    assert!(!text(&out).contains("rendered"), "{}", text(&out));
}

#[test]
fn render_log_has_the_start_progress_and_outcome() {
    let dir = TempDir::new("cli-farm", "render-log");
    let log = dir.join("logs/new/tile.log");
    let out_exr = dir.join("tile.exr");
    let args = ["render", "--size", "8x6", "--spp", "1", "--crop", "0,0,4,6", "-o", out_exr.to_str().unwrap()];
    let out = kelvin(&[&args[..], &["--log", log.to_str().unwrap()]].concat());
    assert!(out.status.success(), "{}", text(&out));
    let lines = std::fs::read_to_string(&log).unwrap();
    let lines: Vec<&str> = lines.lines().collect();
    assert!(lines[0].contains("kelvin render") && lines[0].contains(", pid "), "{lines:?}");
    assert!(lines.iter().any(|l| l.contains("progress 100%:")), "{lines:?}");
    assert!(lines.last().unwrap().contains("rendered"), "{lines:?}");
    // A failure is logged with its exit code, after the earlier run's lines (the log appends).
    let missing = dir.join("no-such-scene.glb");
    let out =
        kelvin(&["render", missing.to_str().unwrap(), "-o", out_exr.to_str().unwrap(), "--log", log.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out));
    let again = std::fs::read_to_string(&log).unwrap();
    assert!(again.starts_with(&lines.join("\n")), "appended: {again}");
    assert!(again.lines().last().unwrap().contains("failed (exit code 2)"), "{again}");
}

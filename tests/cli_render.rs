//! `kelvin render --report`: the summary line, the time of each pass and the light system's run
//! report.

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

/// A light rejected in the render's first update (here an environment light of negative scale)
/// is still in the report after the last batch, and the report's counts cover every batch.
#[test]
fn report_covers_every_batch_of_the_render() {
    let dir = std::env::temp_dir().join(format!("kelvin-cli-render-batches-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let env = dir.join("sky.exr");
    kelvin::render::film_io::write_exr(&env, 4, 2, &[glam::Vec3::ONE; 8]).unwrap();
    let out = dir.join("report.png");
    // 96 x 96 x 4 = 36864 camera samples: three batches of the light system (one update each
    // with direct lighting; the path tracer adds one per bounce).
    let output = Command::new(env!("CARGO_BIN_EXE_kelvin"))
        .args(["render", "-o", out.to_str().unwrap(), "--size", "96x96", "--spp", "4", "--report"])
        .args(["--integrator", "direct"])
        .args(["--env", env.to_str().unwrap(), "--env-intensity=-1"])
        .output()
        .expect("kelvin runs");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    assert!(stderr.contains("warning: environment light") && stderr.contains("scale = -1"), "{stderr}");
    assert!(stderr.contains("36864 points"), "points summed over batches: {stderr}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn light_sampler_defaults_to_the_light_bvh() {
    let output = Command::new(env!("CARGO_BIN_EXE_kelvin")).args(["render", "--help"]).output().expect("kelvin runs");
    let help = String::from_utf8_lossy(&output.stdout);
    let line = help.lines().skip_while(|l| !l.contains("--light-sampler")).take(3).collect::<Vec<_>>().join("\n");
    assert!(line.contains("[default: bvh]"), "{help}");
}

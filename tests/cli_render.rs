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

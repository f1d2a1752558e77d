//! The same render with 1 and 2 threads gives bit-identical EXR output, in both colour modes.

use std::process::Command;

fn render(dir: &std::path::Path, threads: u32, color: &str) -> Vec<u8> {
    let out = dir.join(format!("t{threads}-{color}.exr"));
    let status = Command::new(env!("CARGO_BIN_EXE_kelvin"))
        .args(["render", "-o", out.to_str().unwrap(), "--size", "40x30", "--spp", "4", "--seed", "7"])
        .args(["--threads", &threads.to_string(), "--color", color])
        .output()
        .expect("kelvin runs");
    assert!(status.status.success(), "{}", String::from_utf8_lossy(&status.stderr));
    std::fs::read(&out).unwrap()
}

#[test]
fn one_and_two_threads_give_identical_exr_in_rgb_and_spectral_mode() {
    let dir = std::env::temp_dir().join(format!("kelvin-determinism-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for color in ["rgb", "spectral"] {
        let (a, b) = (render(&dir, 1, color), render(&dir, 2, color));
        assert!(a.len() > 1000, "{color}: EXR written");
        assert!(a == b, "{color}: 1 and 2 threads differ");
    }
    std::fs::remove_dir_all(&dir).ok();
}

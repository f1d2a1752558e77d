//! The same render with 1 and 2 threads gives bit-identical EXR output, in both colour modes and
//! with both integrators.

use std::process::Command;

fn render(dir: &std::path::Path, threads: u32, color: &str, integrator: &str) -> Vec<u8> {
    let out = dir.join(format!("t{threads}-{color}-{integrator}.exr"));
    let status = Command::new(env!("CARGO_BIN_EXE_kelvin"))
        .args(["render", "-o", out.to_str().unwrap(), "--size", "40x30", "--spp", "4", "--seed", "7"])
        .args(["--threads", &threads.to_string(), "--color", color, "--integrator", integrator])
        .output()
        .expect("kelvin runs");
    assert!(status.status.success(), "{}", String::from_utf8_lossy(&status.stderr));
    std::fs::read(&out).unwrap()
}

#[test]
fn one_and_two_threads_give_identical_exr_in_rgb_and_spectral_mode_with_either_integrator() {
    let dir = std::env::temp_dir().join(format!("kelvin-determinism-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (color, integrator) in [("rgb", "path"), ("spectral", "path"), ("rgb", "direct"), ("spectral", "direct")] {
        let (a, b) = (render(&dir, 1, color, integrator), render(&dir, 2, color, integrator));
        assert!(a.len() > 1000, "{color} {integrator}: EXR written");
        let (_, _, pixels) =
            kelvin::render::film_io::read_exr(&dir.join(format!("t2-{color}-{integrator}.exr"))).unwrap();
        assert!(
            pixels.iter().filter(|p| p.max_element() > 0.0).count() > pixels.len() / 2,
            "{color} {integrator}: lit"
        );
        assert!(a == b, "{color} {integrator}: 1 and 2 threads differ");
    }
    std::fs::remove_dir_all(&dir).ok();
}

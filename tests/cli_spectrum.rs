//! `kelvin spectrum` end to end: JSON keys and values, plots, and clear errors.

use std::process::Command;

fn kelvin(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_kelvin")).args(args).output().expect("kelvin runs")
}

#[test]
fn json_has_the_documented_keys_and_values() {
    let out = kelvin(&["spectrum", "blackbody:6500", "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    for key in
        ["xyz", "xy", "uv", "srgb_linear", "cct_k", "duv", "efficacy_lm_per_w", "exitance_w_per_m2", "lambda_max_nm"]
    {
        assert!(v.get(key).is_some(), "missing {key} in {v}");
    }
    assert!((v["cct_k"].as_f64().unwrap() - 6500.0).abs() < 6.5);
    assert!((v["lambda_max_nm"].as_f64().unwrap() - 445.81).abs() < 0.01);
    assert!((v["exitance_w_per_m2"].as_f64().unwrap() / (5.670374419e-8 * 6500f64.powi(4)) - 1.0).abs() < 1e-12);
    assert!((v["xyz"][1].as_f64().unwrap() - 100.0).abs() < 1e-9);

    let out = kelvin(&["spectrum", "illuminant:D65", "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(v.get("exitance_w_per_m2").is_none(), "exitance only for black and grey bodies");
    assert!((v["xy"][0].as_f64().unwrap() - 0.31272).abs() < 2e-4);
}

#[test]
fn csv_spectrum_and_plots() {
    let dir = std::env::temp_dir().join(format!("kelvin-cli-spectrum-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let csv = dir.join("led.csv");
    std::fs::write(&csv, "nm,value\n400,0\n450,1\n500,0.2\n600,0.8\n700,0\n").unwrap();
    for ext in ["svg", "png"] {
        let plot = dir.join(format!("led.{ext}"));
        let out = kelvin(&["spectrum", csv.to_str().unwrap(), "--plot", plot.to_str().unwrap()]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        assert!(std::fs::metadata(&plot).unwrap().len() > 1000, "{ext} plot written");
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn unknown_names_and_bad_csv_give_clear_errors() {
    let out = kelvin(&["spectrum", "illuminant:Z9"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("Z9") && err.contains("F11") && err.contains("D65"), "{err}");

    let out = kelvin(&["spectrum", "plasma:42"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("blackbody:<K>"), "{err}");

    let dir = std::env::temp_dir().join(format!("kelvin-cli-badcsv-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let csv = dir.join("bad.csv");
    std::fs::write(&csv, "400,1\n500\n").unwrap();
    let out = kelvin(&["spectrum", csv.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("line 2") && err.contains("bad.csv"), "{err}");
    let out = kelvin(&["spectrum", dir.join("missing.csv").to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("missing.csv"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

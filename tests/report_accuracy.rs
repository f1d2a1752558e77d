//! `kelvin report accuracy --quick` end to end: the files are written and the numbers are sane
//! (relative MSE falls at least as 1/spp for an unbiased estimator; the reference has no error against
//! itself; RGB rendering under F11 is off the spectral answer by more than noise).

mod common;

use std::path::PathBuf;

use kelvin::report::accuracy::{AccuracyOptions, Budget, Knob, SceneId, run_accuracy};

/// The repository's real test data (the env scene reads its sky from there).
fn data_dir() -> PathBuf {
    common::files::test_data("")
}

#[test]
fn quick_report_is_written_and_its_numbers_are_sane() {
    let out = std::env::temp_dir().join(format!("kelvin-accuracy-test-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let opts = AccuracyOptions { scenes: Vec::new(), out: out.clone(), budget: Budget::QUICK, data_dir: data_dir() };
    let reports = run_accuracy(&opts, &mut |m| eprintln!("{m}")).expect("report runs");
    assert!(out.join("README.md").exists());
    assert_eq!(reports.len(), SceneId::ALL.len(), "{} scenes reported", reports.len());
    assert!(reports.iter().any(|r| r.scene == SceneId::EnvSun), "env-sun scene not reported");

    for r in &reports {
        let name = r.scene.name();
        for file in [format!("{name}.csv"), format!("{name}.md"), format!("{name}-error-vs-time.svg")] {
            let path = out.join(&file);
            let len = std::fs::metadata(&path).map(|m| m.len()).unwrap_or(0);
            assert!(len > 100, "{} missing or empty", path.display());
        }
        let csv = std::fs::read_to_string(out.join(format!("{name}.csv"))).unwrap();
        assert_eq!(csv.lines().count(), r.rows.len() + 2, "{name}: header + rows + reference row");

        // The reference against itself.
        let s = &r.self_check;
        assert_eq!((s.rel_mse, s.max_err), (0.0, 0.0), "{name}: reference vs itself");
        if let Some((mean, max)) = s.de00 {
            assert_eq!((mean, max), (0.0, 0.0), "{name}: reference dE00 vs itself");
        }
        // MSE falls at least as 1/spp on the ladder (1 ... 32 spp against a 512-spp reference), and
        // faster where the default Sobol pattern stratifies smooth light (spp^-1.5 is its rate for
        // smooth integrands; the ladder's few points and the reference's own noise flatten it).
        eprintln!("{name}: slope {:.3}", r.spp_slope);
        assert!((-2.0..=-0.7).contains(&r.spp_slope), "{name}: log MSE / log spp slope {}", r.spp_slope);
        for row in &r.rows {
            assert!(row.seconds > 0.0 && row.rel_mse.is_finite() && row.rel_mse > 0.0, "{name}: {row:?}");
        }
    }

    // RGB under the spiky F11 is biased: its colour error exceeds the spectral baseline's noise,
    // averaged over the patches.
    if let Some(f11) = reports.iter().find(|r| r.scene == SceneId::CheckerF11) {
        let de = |setting: &str| {
            let row = f11.rows.iter().find(|r| r.knob == Knob::Color && r.setting == setting).expect("colour row");
            row.de00.expect("checker rows have dE00").0
        };
        eprintln!("F11: dE00 rgb {:.2}, spectral {:.2}", de("rgb"), de("spectral"));
        assert!(de("rgb") > 0.5, "RGB should be visibly off under F11");
    }
    // A second run reads the cached references back exactly (negative sRGB values of saturated
    // spectral pixels included), so every error is the same.
    let again = AccuracyOptions { scenes: vec![SceneId::CheckerF11], ..opts };
    let second = run_accuracy(&again, &mut |m| eprintln!("{m}")).expect("second run");
    let first = reports.iter().find(|r| r.scene == SceneId::CheckerF11).expect("checker-f11 reported");
    assert!(second[0].references.iter().all(|r| r.cached), "references should come from the cache");
    for (a, b) in first.rows.iter().zip(&second[0].rows) {
        assert_eq!(
            (a.rel_mse, a.de00),
            (b.rel_mse, b.de00),
            "{} {}: cached reference differs",
            a.knob.name(),
            a.setting
        );
    }
    let _ = std::fs::remove_dir_all(&out);
}

/// The colour checker's bookkeeping: under a D65 light in RGB mode each patch's central pixels
/// render its albedo times the luminance of a perfect white diffuser (E cos(theta) / pi).
#[test]
fn color_checker_patches_render_albedo_times_white_luminance() {
    use bevy_ecs::prelude::*;
    use kelvin::render::renderer::{RenderOptions, render};
    use kelvin::report::accuracy::patch_means;
    use kelvin::scenes::color_checker::spawn_color_checker;
    use kelvin::spectrum::Spectrum;
    use kelvin::systems::LightingPlugin;

    let mut world = World::new();
    let mut schedule = Schedule::default();
    LightingPlugin::build(&mut world, &mut schedule);
    let checker = spawn_color_checker(&mut world, Spectrum::d65());
    let (w, h) = (64, 48);
    let (film, _) = render(&mut world, &mut schedule, &RenderOptions::direct(w, h, 1), |_| {});
    let means = patch_means(&film.pixels(), &checker, w, h);
    for (p, m) in checker.patches.iter().zip(&means) {
        let want = p.albedo.as_dvec3() * checker.white_luminance as f64;
        assert!((*m - want).abs().max_element() < 1e-3 * want.max_element().max(1.0), "{}: {m} vs {want}", p.name);
    }
}

//! Sun and sky with the sun on against an independent renderer (issue 57, item 8): Mitsuba 3.9.1's
//! `sunsky` emitter, integrated by bench/mitsuba/sunsky_reference.py into the spectral irradiance
//! of its sky on a horizontal surface and of its sun on a surface facing it, at the Hosek-Wilkie
//! model wavelengths (tests/data/sunsky/mitsuba_sunsky_irradiance.csv; tests/data/SOURCES.md).
//! kelvin's light, integrated the same way, is within 2% of it at every wavelength, and so are
//! the illuminances (683 x the integral of E ybar over 360-720 nm, E linear between the model
//! wavelengths as both renderers interpolate).
//!
//! The sun is compared with Mitsuba's `complex_sun` (the 2013 model's radiance with limb
//! darkening, as kelvin's): kelvin's is 1.1% below it, the ratio of the discs' solid angles
//! (kelvin's sun is 0.0093 rad = 0.533 degrees across, the mean apparent diameter; Mitsuba's
//! 0.5358 degrees). Mitsuba's default sun (its irradiance tabulated at 30 elevations, linear
//! between) is printed too: in illuminance it is within 1% of kelvin's, but its UV is up to 18%
//! higher at low suns (320 nm at 10 degrees), where the tabulation's linear interpolation
//! overshoots a convex curve.

mod common;

use std::f64::consts::PI;

use glam::{DVec3, Vec3};
use kelvin::light::infinite::sunsky::{SunPosition, SunSkyLight, WAVELENGTHS_NM, direction_from_angles};
use kelvin::light::{ColorQuery, ResolvedSunSky, SceneSphere};
use kelvin::sampling::Frame;
use kelvin::spectrum::SampledWavelengths;
use kelvin::spectrum::cie::CIE_1931;

struct Row {
    turbidity: f32,
    albedo: f32,
    elevation: f64,
    sky_h: [f64; 11],
    sun_n: [f64; 11],
    sun_n_ld: [f64; 11],
}

fn reference() -> Vec<Row> {
    let path = common::files::test_data("sunsky/mitsuba_sunsky_irradiance.csv");
    let text = std::fs::read_to_string(&path).unwrap();
    let mut rows: Vec<Row> = Vec::new();
    for line in text.lines().filter(|l| !l.starts_with('#') && !l.starts_with("turbidity")) {
        let f: Vec<&str> = line.split(',').collect();
        assert_eq!(f.len(), 15, "{}: {line}", path.display());
        let num = |s: &str| s.parse::<f64>().unwrap_or_else(|_| panic!("{}: '{s}' in {line}", path.display()));
        let (t, a, e) = (num(f[0]) as f32, num(f[1]) as f32, num(f[2]));
        let values: [f64; 11] = std::array::from_fn(|i| num(f[4 + i]));
        if !rows.last().is_some_and(|r| (r.turbidity, r.albedo, r.elevation) == (t, a, e)) {
            let z = [0.0; 11];
            rows.push(Row { turbidity: t, albedo: a, elevation: e, sky_h: z, sun_n: z, sun_n_ld: z });
        }
        let row = rows.last_mut().unwrap();
        match f[3] {
            "sky_h" => row.sky_h = values,
            "sun_n" => row.sun_n = values,
            "sun_n_ld" => row.sun_n_ld = values,
            other => panic!("{}: unknown quantity {other}", path.display()),
        }
    }
    assert!(rows.len() >= 5 && rows.iter().all(|r| r.sky_h[5] > 0.0 && r.sun_n[5] > 0.0), "{}", path.display());
    rows
}

/// Spectral radiance of `light` toward `w` at the 11 model wavelengths.
fn le11(light: &ResolvedSunSky, w: Vec3) -> [f64; 11] {
    let mut out = [0.0; 11];
    for k in (0..11).step_by(4) {
        let lambda: [f32; 4] = std::array::from_fn(|i| WAVELENGTHS_NM[(k + i).min(10)]);
        let l = light.le(w, ColorQuery::Spectral(&SampledWavelengths { lambda, pdf: [1.0; 4] })).0;
        for i in 0..4.min(11 - k) {
            out[k + i] = l[i] as f64;
        }
    }
    out
}

/// The sky's horizontal irradiance: its model over the upper hemisphere in sun-centred
/// coordinates (gamma = pi s^2 refines the circumsolar peak), midpoint rule, as the script does.
fn sky_horizontal(light: &ResolvedSunSky) -> [f64; 11] {
    let sky = light.sky.as_ref().unwrap();
    let frame = Frame::from_z(light.sun_dir);
    let (ng, np) = (320, 384);
    let mut e = [0.0; 11];
    for i in 0..ng {
        let s = (i as f64 + 0.5) / ng as f64;
        let (g, dg) = (PI * s * s, 2.0 * PI * s / ng as f64);
        for j in 0..np {
            let p = 2.0 * PI * (j as f64 + 0.5) / np as f64;
            let local = DVec3::new(g.sin() * p.cos(), g.sin() * p.sin(), g.cos()).as_vec3();
            let w = frame.from_local(local).normalize();
            if w.y <= 0.0 {
                continue;
            }
            let weight = w.y as f64 * g.sin() * dg * 2.0 * PI / np as f64;
            for (k, lambda) in WAVELENGTHS_NM.iter().enumerate() {
                e[k] += sky.spectral(*lambda, w, light.sun_dir) as f64 * weight;
            }
        }
    }
    e
}

/// The sun's normal irradiance: le less the sky over its disc, uniform in solid angle.
fn sun_normal(light: &ResolvedSunSky) -> [f64; 11] {
    let (sun, sky) = (light.sun.as_ref().unwrap(), light.sky.as_ref().unwrap());
    let frame = Frame::from_z(sun.dir);
    let (nr, np) = (48, 48);
    let cos_max = 1.0 - sun.one_minus_cos as f64;
    let mut e = [0.0; 11];
    for i in 0..nr {
        let c = 1.0 - (i as f64 + 0.5) / nr as f64 * (1.0 - cos_max);
        let sg = (1.0 - c * c).max(0.0).sqrt();
        for j in 0..np {
            let p = 2.0 * PI * (j as f64 + 0.5) / np as f64;
            let w = frame.from_local(DVec3::new(sg * p.cos(), sg * p.sin(), c).as_vec3()).normalize();
            let l = le11(light, w);
            for (k, lambda) in WAVELENGTHS_NM.iter().enumerate() {
                let disc = l[k] - sky.spectral(*lambda, w, light.sun_dir) as f64;
                e[k] += disc * sun.solid_angle() as f64 / (nr * np) as f64;
            }
        }
    }
    e
}

/// 683 x the integral of E ybar over 360-720 nm, E linear between the model wavelengths.
fn lux(e: &[f64; 11]) -> f64 {
    (360..=720usize)
        .map(|nm| {
            let t = (nm as f64 - 320.0) / 40.0;
            let i = (t.floor() as usize).min(9);
            let f = t - i as f64;
            (e[i] + f * (e[i + 1] - e[i])) * CIE_1931.at_nm(nm)[1]
        })
        .sum::<f64>()
        * 683.0
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b) / b
}

#[test]
fn sun_and_sky_match_mitsuba_sunsky_within_two_percent() {
    let mut worst = [0.0f64; 4];
    let mut failures = Vec::new();
    for row in reference() {
        let light = SunSkyLight {
            sun: SunPosition::Direction(direction_from_angles(row.elevation, 180.0)),
            turbidity: row.turbidity,
            ground_albedo: row.albedo,
            ..Default::default()
        }
        .resolve(SceneSphere::default())
        .unwrap();
        let (sky, sun) = (sky_horizontal(&light), sun_normal(&light));
        let sin_e = row.elevation.to_radians().sin();
        let total = |s: &[f64; 11], n: &[f64; 11]| -> [f64; 11] { std::array::from_fn(|k| s[k] + n[k] * sin_e) };
        let (mine, theirs) = (total(&sky, &sun), total(&row.sky_h, &row.sun_n_ld));
        let name = format!("T {} albedo {} elevation {}", row.turbidity, row.albedo, row.elevation);
        let lux_pairs = [
            ("sky lx", lux(&sky), lux(&row.sky_h)),
            ("sun lx", lux(&sun), lux(&row.sun_n_ld)),
            ("sun+sky horizontal lx", lux(&mine), lux(&theirs)),
        ];
        eprint!("{name}:");
        for (what, a, b) in lux_pairs {
            eprint!(" {what} {a:.0} vs {b:.0} ({:+.2}%);", 100.0 * rel(a, b));
            worst[0] = worst[0].max(rel(a, b).abs());
            if rel(a, b).abs() > 0.02 {
                failures.push(format!("{name}: {what} {a:.1} vs Mitsuba {b:.1} ({:+.2}%)", 100.0 * rel(a, b)));
            }
        }
        let plain =
            (0..11).map(|k| rel(sun[k], row.sun_n[k])).fold(0.0f64, |a, r| if r.abs() > a.abs() { r } else { a });
        eprintln!(
            " vs Mitsuba's default sun: {:+.2}% in lx, worst wavelength {:+.2}%",
            100.0 * rel(lux(&sun), lux(&row.sun_n)),
            100.0 * plain
        );
        // Per wavelength, relative to the value or to 1% of the series' peak, whichever is larger:
        // near the horizon the sun's UV is ~1e-5 of its peak, where 2% of it is no light at all.
        let peak = |v: &[f64; 11]| v.iter().copied().fold(0.0f64, f64::max);
        let (sky_peak, sun_peak, total_peak) = (peak(&row.sky_h), peak(&row.sun_n_ld), peak(&theirs));
        let rel_to = |a: f64, b: f64, peak: f64| (a - b) / b.abs().max(0.01 * peak);
        for k in 0..11 {
            for (what, a, b, slot, peak) in [
                ("sky", sky[k], row.sky_h[k], 1, sky_peak),
                ("sun", sun[k], row.sun_n_ld[k], 2, sun_peak),
                ("sun+sky", mine[k], theirs[k], 3, total_peak),
            ] {
                let rel = |a: f64, b: f64| rel_to(a, b, peak);
                worst[slot] = worst[slot].max(rel(a, b).abs());
                if rel(a, b).abs() > 0.02 {
                    let nm = WAVELENGTHS_NM[k];
                    failures.push(format!(
                        "{name}: {what} at {nm} nm {a:.5} vs Mitsuba {b:.5} ({:+.2}%)",
                        100.0 * rel(a, b)
                    ));
                }
            }
        }
    }
    eprintln!(
        "worst: illuminance {:.2}%, sky {:.2}%, sun {:.2}%, sun+sky {:.2}% (per wavelength)",
        100.0 * worst[0],
        100.0 * worst[1],
        100.0 * worst[2],
        100.0 * worst[3]
    );
    assert!(failures.is_empty(), "{} beyond 2%:\n{}", failures.len(), failures.join("\n"));
}

//! Sun and sky, the hard cases and the sampling: the sun below the horizon, turbidity at the
//! tables' ends and beyond, the poles, bad parameters; Sample_Li's pdf against pdf_li, the pdf
//! integrating to 1, chi-square of the sampled directions, Monte Carlo irradiance against
//! quadrature in both colour modes, and the ECS rebuilding the table only when the light changes.

mod common;
#[path = "sampling/common.rs"]
#[allow(dead_code)]
mod sampling_common;

use std::f64::consts::PI;

use bevy_ecs::prelude::*;
use glam::{Vec2, Vec3};
use kelvin::light::infinite::sunsky::{
    SkyModel, SunModel, SunPosition, SunSkyLight, UtcDateTime, direction_from_angles, solar_position,
};
use kelvin::light::{ColorQuery, LightKind, LightSampleContext, LightTable, ResolvedSunSky, SceneSphere};
use kelvin::rng::SplitMix64;
use kelvin::scene::image::{LUMINANCE_WEIGHTS, direction_to_lat_long, lat_long_direction};
use kelvin::shading::{ColorMode, DirectLighting, RunReport, Settings, ShadingBatch};
use kelvin::spectrum::SampledWavelengths;
use kelvin::systems::LightingPlugin;
use sampling_common::assert_chi_square;

fn toward(elevation: f64, azimuth: f64) -> SunSkyLight {
    SunSkyLight { sun: SunPosition::Direction(direction_from_angles(elevation, azimuth)), ..Default::default() }
}

fn resolve(light: &SunSkyLight) -> ResolvedSunSky {
    light.resolve(SceneSphere::default()).unwrap()
}

fn random_dir(rng: &mut SplitMix64) -> Vec3 {
    kelvin::sampling::sample_uniform_sphere(Vec2::new(rng.f32(), rng.f32()))
}

#[test]
fn sun_past_civil_twilight_is_a_black_light_without_nan() {
    let w = SampledWavelengths::sample_visible(0.6);
    // The sky fades out by the end of civil twilight, -6 degrees (tests/lights_sunsky_twilight.rs).
    for light in [toward(-6.5, 180.0), toward(-30.0, 90.0), toward(-90.0, 0.0)] {
        let r = resolve(&light);
        assert!(r.is_night() && r.sun.is_none());
        assert_eq!((r.phi(), r.luminous_phi(), r.sun_illuminance()), (0.0, 0.0, 0.0));
        let mut rng = SplitMix64::new(1);
        let ctx = LightSampleContext::on_surface(Vec3::ZERO, Vec3::Y);
        for _ in 0..1000 {
            let d = random_dir(&mut rng);
            assert_eq!(r.pdf_li(d), 0.0);
            for q in [ColorQuery::Rgb, ColorQuery::Spectral(&w)] {
                assert!(r.le(d, q).0.iter().all(|&v| v == 0.0));
                assert!(r.sample_li(&ctx, Vec2::new(rng.f32(), rng.f32()), q).is_none());
            }
        }
    }
    // Midnight at Greenwich in December, from the date.
    let t = UtcDateTime::parse("2024-12-21T00:00").unwrap();
    assert!(resolve(&SunSkyLight::at(51.48, 0.0, t)).is_night());
}

#[test]
fn sun_at_the_horizon_gives_finite_light() {
    for e in [0.0, 0.01, 0.3] {
        let r = resolve(&toward(e, 100.0));
        let w = SampledWavelengths::sample_visible(0.2);
        for d in [Vec3::new(0.0, 1e-6, 1.0).normalize(), Vec3::Y, r.sun_dir, Vec3::new(1.0, 0.01, 0.0).normalize()] {
            for q in [ColorQuery::Rgb, ColorQuery::Spectral(&w)] {
                assert!(r.le(d, q).0.iter().all(|v| v.is_finite() && *v >= 0.0), "elevation {e}, {d}");
            }
            assert!(r.pdf_li(d).is_finite());
        }
        assert!(r.phi().is_finite() && r.luminous_phi().is_finite());
    }
}

#[test]
fn turbidity_at_the_table_ends_and_clamped_beyond() {
    let e = 0.6f32;
    for t in [1.0f32, 10.0] {
        let r = resolve(&SunSkyLight { turbidity: t, ..toward(e.to_degrees() as f64, 180.0) });
        let l = r.le(Vec3::new(0.3, 0.8, 0.1).normalize(), ColorQuery::Rgb);
        assert!(l.0[..3].iter().all(|v| v.is_finite() && *v > 0.0), "turbidity {t}: {l:?}");
        assert!(r.sun_illuminance() > 0.0 && r.sun_illuminance().is_finite());
    }
    // The model clamps to its tables: below 1 is 1, above 10 is 10.
    assert_eq!(SkyModel::new(e, 0.2, 0.3), SkyModel::new(e, 1.0, 0.3));
    assert_eq!(SkyModel::new(e, 14.0, 0.3), SkyModel::new(e, 10.0, 0.3));
    assert_eq!(SkyModel::new(e, f32::NAN, 0.3), SkyModel::new(e, 1.0, 0.3));
    assert_eq!(SunModel::new(e, 11.0), SunModel::new(e, 10.0));
    assert_eq!(SkyModel::new(2.0, 3.0, 1.5), SkyModel::new(std::f32::consts::FRAC_PI_2, 3.0, 1.0));
    // Hazier skies dim the sun.
    let sun = |t| resolve(&SunSkyLight { turbidity: t, ..toward(40.0, 180.0) }).sun_illuminance();
    assert!(sun(1.0) > sun(5.0) && sun(5.0) > sun(10.0));
}

#[test]
fn bad_parameters_are_errors_that_name_the_field() {
    let cases: [(SunSkyLight, &str); 9] = [
        (SunSkyLight { turbidity: 10.5, ..Default::default() }, "turbidity"),
        (SunSkyLight { turbidity: 0.9, ..Default::default() }, "turbidity"),
        (SunSkyLight { turbidity: f32::NAN, ..Default::default() }, "turbidity"),
        (SunSkyLight { ground_albedo: 1.5, ..Default::default() }, "ground_albedo"),
        (SunSkyLight { sun_angular_diameter: 0.0, ..Default::default() }, "sun_angular_diameter"),
        (SunSkyLight { scale: -1.0, ..Default::default() }, "scale"),
        (SunSkyLight { table_width: 2, ..Default::default() }, "table_width"),
        (SunSkyLight { sun: SunPosition::Direction(Vec3::ZERO), ..Default::default() }, "sun direction"),
        (SunSkyLight { sun: SunPosition::Direction(Vec3::NAN), ..Default::default() }, "sun direction"),
    ];
    for (light, field) in cases {
        let e = light.resolve(SceneSphere::default()).expect_err(field).to_string();
        assert!(e.contains(field), "{field}: {e}");
    }
}

#[test]
fn the_poles_have_a_sun_at_plus_or_minus_its_declination() {
    for time in ["2024-03-20T03:06", "2024-06-21T00:00", "2024-06-21T13:30", "2024-09-22T18:00", "2024-12-21T07:45"] {
        let t = UtcDateTime::parse(time).unwrap();
        for lat in [90.0, -90.0] {
            for lon in [0.0, 123.0, -180.0] {
                let p = solar_position(lat, lon, &t).unwrap();
                // At a pole the hour angle drops out: sin(elevation) = sin(lat) sin(declination).
                let want = if lat > 0.0 { p.declination_deg } else { -p.declination_deg };
                assert!((p.elevation_deg - want).abs() < 1e-9, "{time} at {lat}: {} vs {want}", p.elevation_deg);
                assert!(p.direction().is_finite() && (p.direction().length() - 1.0).abs() < 1e-5);
                let r = resolve(&SunSkyLight::at(lat, lon, t));
                assert_eq!(r.is_night(), p.elevation_deg <= -6.0, "{time} at {lat}");
                assert!(r.luminous_phi().is_finite());
            }
        }
    }
}

#[test]
fn sample_li_pdf_and_radiance_are_pdf_li_and_le_at_the_sample() {
    let w = SampledWavelengths::sample_visible(0.45);
    for light in [toward(35.0, 200.0), toward(2.0, 90.0), toward(80.0, 0.0)] {
        let r = resolve(&light);
        let ctx = LightSampleContext::on_surface(Vec3::new(0.2, 0.0, 0.1), Vec3::Y);
        let mut rng = SplitMix64::new(9);
        let (mut sun_hits, mut n) = (0, 0);
        for _ in 0..20_000 {
            let u = Vec2::new(rng.f32(), rng.f32());
            for q in [ColorQuery::Rgb, ColorQuery::Spectral(&w)] {
                let Some(s) = r.sample_li(&ctx, u, q) else { continue };
                assert_eq!(s.pdf, r.pdf_li(s.wi));
                assert_eq!(s.radiance, r.le(s.wi, q));
                assert!(s.radiance.0.iter().all(|v| v.is_finite()));
                n += 1;
                sun_hits += (s.wi.dot(r.sun_dir) > 0.9999) as usize;
            }
        }
        let frac = sun_hits as f64 / n as f64;
        assert!((frac - r.p_sun as f64).abs() < 0.02, "sun fraction {frac} vs p_sun {}", r.p_sun);
    }
}

/// Integral of `f` over the upper hemisphere on a w x w/2... lat-long midpoint grid of `w`
/// columns and `h` rows (each cell's exact solid angle).
fn quadrature(w: usize, h: usize, f: impl Fn(Vec3) -> f64) -> f64 {
    let mut sum = 0.0;
    for y in 0..h {
        let (t0, t1) = (PI * y as f64 / h as f64, PI * (y + 1) as f64 / h as f64);
        let d_omega = 2.0 * PI / w as f64 * (t0.cos() - t1.cos());
        for x in 0..w {
            let d = lat_long_direction(Vec2::new((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32));
            sum += f(d) * d_omega;
        }
    }
    sum
}

#[test]
fn the_pdf_integrates_to_one() {
    let r = resolve(&toward(33.0, 200.0));
    let tables = r.buffers.tables.as_ref().unwrap();
    // The sky table's density is constant per texel (512 x 256): a grid of 4 x 4 cells per texel
    // integrates it exactly.
    let sky = quadrature(2048, 1024, |d| tables.pdf_direction(d, false) as f64);
    assert!((sky - 1.0).abs() < 1e-4, "sky table: {sky}");
    // The sun's part of the mixture over a polar grid on its cone (1.5 radii).
    let sun = r.sun.as_ref().unwrap();
    let frame = kelvin::sampling::Frame::from_z(sun.dir);
    // 300 rings over 1.5 radii put the disc's rim on a ring edge.
    let (radius, n) = (1.5 * (sun.sin2_radius as f64).sqrt().asin(), 300);
    let mut cone = 0.0;
    for i in 0..n {
        let (a0, a1) = (radius * i as f64 / n as f64, radius * (i + 1) as f64 / n as f64);
        let a = 0.5 * (a0 + a1);
        for j in 0..n {
            let phi = 2.0 * PI * (j as f64 + 0.5) / n as f64;
            let local = Vec3::new((a.sin() * phi.cos()) as f32, (a.sin() * phi.sin()) as f32, a.cos() as f32);
            let d = frame.from_local(local).normalize();
            let sun_part = r.pdf_li(d) as f64 - (1.0 - r.p_sun as f64) * tables.pdf_direction(d, false) as f64;
            cone += sun_part * 2.0 * PI / n as f64 * (a0.cos() - a1.cos());
        }
    }
    let total = (1.0 - r.p_sun as f64) * sky + cone;
    eprintln!("p_sun {}, sun part {cone}, total {total}", r.p_sun);
    assert!((cone - r.p_sun as f64).abs() < 2e-3 * r.p_sun as f64, "sun part {cone} vs {}", r.p_sun);
    assert!((total - 1.0).abs() < 2e-3, "{total}");
}

#[test]
fn sampled_directions_pass_chi_square() {
    let r = resolve(&toward(33.0, 200.0));
    let tables = r.buffers.tables.as_ref().unwrap();
    let (bw, bh, sub) = (32usize, 16usize, 16usize);
    let bin = |d: Vec3| {
        let uv = direction_to_lat_long(d);
        ((uv.y * bh as f32) as usize).min(bh - 1) * bw + ((uv.x * bw as f32) as usize).min(bw - 1)
    };
    // Expected: the sky's mass per bin by quadrature (exact: the table is a multiple of the bins),
    // plus p_sun in the bin holding the whole disc.
    let mut probs = vec![0.0f64; bw * bh];
    let (w, h) = (bw * sub, bh * sub);
    for y in 0..h {
        let (t0, t1) = (PI * y as f64 / h as f64, PI * (y + 1) as f64 / h as f64);
        for x in 0..w {
            let d = lat_long_direction(Vec2::new((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32));
            let m = tables.pdf_direction(d, false) as f64 * 2.0 * PI / w as f64 * (t0.cos() - t1.cos());
            probs[(y / sub) * bw + x / sub] += (1.0 - r.p_sun as f64) * m;
        }
    }
    let sun = r.sun.as_ref().unwrap();
    let frame = kelvin::sampling::Frame::from_z(sun.dir);
    let rim = (sun.sin2_radius as f64).sqrt() as f32;
    let sun_bin = bin(sun.dir);
    for k in 0..16 {
        let a = k as f32 * std::f32::consts::TAU / 16.0;
        let d = frame.from_local(Vec3::new(rim * a.cos(), rim * a.sin(), 1.0)).normalize();
        assert_eq!(bin(d), sun_bin, "the sun's disc must lie in one bin for this test");
    }
    probs[sun_bin] += r.p_sun as f64;
    let ctx = LightSampleContext::at(Vec3::ZERO);
    let mut counts = vec![0u64; bw * bh];
    let mut rng = SplitMix64::new(5);
    for _ in 0..400_000 {
        if let Some(s) = r.sample_li(&ctx, Vec2::new(rng.f32(), rng.f32()), ColorQuery::Rgb) {
            counts[bin(s.wi)] += 1;
        }
    }
    let stat = assert_chi_square("sun and sky directions", &counts, &probs);
    eprintln!("chi-square {stat:.1} over {} bins", probs.iter().filter(|&&p| p > 0.0).count());
}

#[test]
fn monte_carlo_irradiance_matches_quadrature_in_both_modes() {
    let r = resolve(&toward(25.0, 150.0));
    let w = SampledWavelengths::sample_visible(0.7);
    let sun = r.sun.as_ref().unwrap();
    for n in [Vec3::Y, Vec3::new(0.0, 0.5, -1.0).normalize(), Vec3::new(1.0, 0.2, 0.5).normalize()] {
        let ctx = LightSampleContext::on_surface(Vec3::ZERO, n);
        for (name, q, channel) in [("RGB Y", ColorQuery::Rgb, None), ("spectral", ColorQuery::Spectral(&w), Some(0))] {
            let value = |s: kelvin::spectrum::SampledSpectrum| match channel {
                None => common::lum(s),
                Some(c) => s.0[c] as f64,
            };
            // The sky by quadrature (le minus the sun inside the disc is the sky alone); the sun by
            // its closed form (the disc is far smaller than a grid cell).
            let sky = quadrature(1024, 512, |d| {
                let in_sun = sun.dir.dot(d) > 0.9999;
                if in_sun { 0.0 } else { value(r.le(d, q)) * n.dot(d).max(0.0) as f64 }
            });
            let disc = {
                let frame = kelvin::sampling::Frame::from_z(sun.dir);
                let mut rng = SplitMix64::new(2);
                let mut acc = 0.0;
                for _ in 0..4000 {
                    let l =
                        kelvin::sampling::sample_uniform_cone_sin2(Vec2::new(rng.f32(), rng.f32()), sun.sin2_radius);
                    let d = frame.from_local(l).normalize();
                    acc += value(r.le(d, q)) * n.dot(d).max(0.0) as f64 * sun.solid_angle() as f64;
                }
                acc / 4000.0
            };
            let mut rng = SplitMix64::new(11);
            let mut e = common::Stats::default();
            for _ in 0..200_000 {
                let v = r
                    .sample_li(&ctx, Vec2::new(rng.f32(), rng.f32()), q)
                    .map_or(0.0, |s| value(s.radiance) * n.dot(s.wi).max(0.0) as f64 / s.pdf as f64);
                e.add(v);
            }
            e.check(&format!("{name} irradiance, normal {n}"), sky + disc, 5e-3 * (sky + disc));
        }
    }
}

fn world(mode: ColorMode) -> (World, Schedule) {
    let mut world = World::new();
    let mut schedule = Schedule::default();
    world.insert_resource(Settings { color_mode: mode, ..Default::default() });
    LightingPlugin::build(&mut world, &mut schedule);
    (world, schedule)
}

fn pixels_ptr(world: &World, e: Entity) -> *const Vec3 {
    world.resource::<LightTable>().sun_sky_of(e).unwrap().buffers.image.pixels.as_ptr()
}

#[test]
fn the_ecs_rebuilds_the_sky_only_when_it_changes_and_reuses_its_buffers() {
    for mode in [ColorMode::Rgb, ColorMode::Spectral] {
        let (mut world, mut schedule) = world(mode);
        let e = world.spawn(toward(30.0, 180.0)).id();
        let mut batch = world.resource_mut::<ShadingBatch>();
        batch.push(Vec3::ZERO, Vec3::Y, 0, 0);
        if mode == ColorMode::Spectral {
            batch.wavelengths.push(SampledWavelengths::sample_visible(0.5));
        }
        schedule.run(&mut world);
        let table = world.resource::<LightTable>();
        assert_eq!(table.kind_len(LightKind::SunSky), 1);
        let (generation, ptr) = (table.generation(), pixels_ptr(&world, e));
        let direct = world.resource::<DirectLighting>();
        assert!(direct.radiance.iter().all(|s| s.is_finite()) && direct.len() == 1);

        schedule.run(&mut world);
        assert_eq!(world.resource::<LightTable>().generation(), generation, "nothing changed: no upsert");

        world.get_mut::<SunSkyLight>(e).unwrap().sun = SunPosition::Direction(direction_from_angles(50.0, 210.0));
        schedule.run(&mut world);
        let table = world.resource::<LightTable>();
        assert!(table.generation() > generation);
        let row = table.sun_sky_of(e).unwrap();
        assert!((row.sun_dir - direction_from_angles(50.0, 210.0)).length() < 1e-6);
        assert_eq!(pixels_ptr(&world, e), ptr, "the rebuild reused the image buffer");

        // Night: the light stays, black, with no NaN, and a warning says why it is dark.
        world.get_mut::<SunSkyLight>(e).unwrap().sun = SunPosition::Direction(direction_from_angles(-10.0, 0.0));
        schedule.run(&mut world);
        let warnings = &world.resource::<RunReport>().warnings;
        assert!(
            warnings.len() == 1
                && warnings[0].contains("the sun is 10.0 degrees below the horizon: the sun and sky give no light"),
            "{warnings:?}"
        );
        assert!(world.resource::<LightTable>().sun_sky_of(e).unwrap().is_night());
        let direct = world.resource::<DirectLighting>();
        assert!(direct.radiance.iter().all(|s| s.is_finite() && s.0.iter().all(|&v| v == 0.0)));

        // A bad change is a warning and removes the row; removing the component removes it too.
        world.get_mut::<SunSkyLight>(e).unwrap().turbidity = 40.0;
        schedule.run(&mut world);
        assert!(world.resource::<RunReport>().warnings.iter().any(|w| w.contains("turbidity")));
        assert_eq!(world.resource::<LightTable>().kind_len(LightKind::SunSky), 0);
        world.get_mut::<SunSkyLight>(e).unwrap().turbidity = 3.0;
        schedule.run(&mut world);
        assert_eq!(world.resource::<LightTable>().kind_len(LightKind::SunSky), 1);
        world.entity_mut(e).remove::<SunSkyLight>();
        schedule.run(&mut world);
        assert_eq!(world.resource::<LightTable>().kind_len(LightKind::SunSky), 0);
        let _ = LUMINANCE_WEIGHTS;
    }
}

#[test]
fn the_sky_table_image_is_the_model_at_texel_centres() {
    let r = resolve(&SunSkyLight { table_width: 64, ..toward(20.0, 135.0) });
    let (img, sky) = (&r.buffers.image, r.sky.as_ref().unwrap());
    assert_eq!((img.width, img.height), (64, 32));
    for y in 0..img.height {
        for x in 0..img.width {
            let uv = Vec2::new((x as f32 + 0.5) / 64.0, (y as f32 + 0.5) / 32.0);
            // Below the horizon: the light's ground (tests/lights_sunsky_twilight.rs checks its value).
            let below = 2 * y >= img.height;
            let want = if below { r.ground_rgb } else { sky.rgb_nits(lat_long_direction(uv), r.sun_dir) };
            let got = img.get(x, y);
            assert!(
                (got - want).abs().max_element() <= 1e-4 * want.max_element().max(1e-3),
                "({x}, {y}): {got} vs {want}"
            );
            assert!(got.min_element() > 0.0, "({x}, {y}) is lit");
        }
    }
}

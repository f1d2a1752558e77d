//! A day of sun and sky: moves a `SunSkyLight` over a day (Paris by default, every 15 minutes,
//! UTC) through the light system and reports what each frame's table rebuild costs, with the
//! sun's elevation and the daylight on a horizontal surface at each hour.
//! `cargo run --release --example sky_timelapse [TABLE_WIDTH] [LAT,LON,YYYY-MM-DD]`
//!
//! Per frame it times the schedule's update with the light changed (the sync system evaluates
//! the sky model into the kept image and rebuilds its tables into their buffers) and with the
//! light unchanged (change detection: nothing rebuilt).

use std::time::Instant;

use bevy_ecs::prelude::*;
use glam::{Vec2, Vec3};
use kelvin::light::infinite::sunsky::{SunPosition, SunSkyLight, UtcDateTime};
use kelvin::light::{ColorQuery, LightSampleContext, LightTable};
use kelvin::rng::SplitMix64;
use kelvin::systems::LightingPlugin;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let width: usize = args.iter().find_map(|a| a.parse().ok()).unwrap_or(512);
    let place = args.iter().find(|a| a.contains(',')).cloned().unwrap_or_else(|| "48.86,2.35,2024-06-21".into());
    let parts: Vec<&str> = place.split(',').collect();
    let (lat, lon, date) = match parts[..] {
        [lat, lon, date] => (lat.parse::<f64>().expect("latitude"), lon.parse::<f64>().expect("longitude"), date),
        _ => panic!("expected LAT,LON,YYYY-MM-DD, got {place}"),
    };
    let time = |minutes: u32| UtcDateTime::parse(&format!("{date}T{:02}:{:02}", minutes / 60, minutes % 60)).unwrap();

    let mut world = World::new();
    let mut schedule = Schedule::default();
    LightingPlugin::build(&mut world, &mut schedule);
    let light = SunSkyLight { table_width: width, ..SunSkyLight::at(lat, lon, time(0)) };
    let e = world.spawn(light).id();
    schedule.run(&mut world); // first build: allocates the buffers

    let (mut changed, mut unchanged) = (Vec::new(), Vec::new());
    println!("sky table {width} x {}, {place}, every 15 min UTC", width.div_ceil(4) * 2);
    println!("  UTC    elevation  p_sun   sun lx   sky+sun on horizontal lx   rebuild ms");
    for frame in 0..96u32 {
        let t = time(frame * 15);
        world.get_mut::<SunSkyLight>(e).unwrap().sun =
            SunPosition::Location { latitude_deg: lat, longitude_deg: lon, time: t };
        let start = Instant::now();
        schedule.run(&mut world);
        let ms = start.elapsed().as_secs_f64() * 1e3;
        let night = world.resource::<LightTable>().sun_sky_of(e).is_none_or(|r| r.is_night());
        if !night {
            changed.push(ms);
        }
        let start = Instant::now();
        schedule.run(&mut world);
        unchanged.push(start.elapsed().as_secs_f64() * 1e3);
        if frame % 4 == 0 {
            let table = world.resource::<LightTable>();
            let row = table.sun_sky_of(e).expect("the light is in the table");
            let elevation = row.sun_dir.y.clamp(-1.0, 1.0).asin().to_degrees();
            println!(
                "  {:02}:00  {elevation:8.2}  {:5.3}  {:8.0}  {:12.0}  {ms:19.2}",
                frame / 4,
                row.p_sun,
                row.sun_illuminance(),
                horizontal_lux(row)
            );
        }
    }
    let stats = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        (v[v.len() / 2], v[v.len() - 1])
    };
    let (med, max) = stats(&mut changed);
    let (umed, _) = stats(&mut unchanged);
    println!(
        "per-frame update with the sun moved: median {med:.2} ms, max {max:.2} ms ({} daytime frames)",
        changed.len()
    );
    println!("per-frame update with nothing changed: median {umed:.3} ms");

    // The rebuild at noon, split: the whole resolve (model into the image, then the tables) and
    // the tables alone, each into reused buffers, best of 20.
    let noon = SunSkyLight { table_width: width, ..SunSkyLight::at(lat, lon, time(12 * 60)) };
    let scene = kelvin::light::SceneSphere::default();
    let mut buffers = noon.resolve(scene).unwrap().into_buffers();
    let (mut whole, mut tables) = (f64::INFINITY, f64::INFINITY);
    for _ in 0..20 {
        let start = Instant::now();
        let row = noon.resolve_reusing(scene, buffers).unwrap();
        whole = whole.min(start.elapsed().as_secs_f64() * 1e3);
        buffers = row.into_buffers();
        let options = kelvin::light::EnvTableOptions {
            compensate: false,
            max_width: None,
            lookup: kelvin::light::EnvLookup::Nearest,
        };
        let start = Instant::now();
        buffers.tables.as_mut().unwrap().rebuild(&buffers.image, options);
        tables = tables.min(start.elapsed().as_secs_f64() * 1e3);
    }
    println!(
        "noon rebuild, best of 20: {whole:.2} ms in all, of which the tables {tables:.2} ms and the sky model {:.2} ms",
        whole - tables
    );
}

/// Illuminance on an upward surface, lx: Monte Carlo through the light's Sample_Li.
fn horizontal_lux(light: &kelvin::light::ResolvedSunSky) -> f64 {
    let ctx = LightSampleContext::on_surface(Vec3::ZERO, Vec3::Y);
    let mut rng = SplitMix64::new(1);
    let n = 4096;
    let sum: f64 = (0..n)
        .map(|_| {
            light.sample_li(&ctx, Vec2::new(rng.f32(), rng.f32()), ColorQuery::Rgb).map_or(0.0, |s| {
                let y = 0.2126 * s.radiance.0[0] + 0.7152 * s.radiance.0[1] + 0.0722 * s.radiance.0[2];
                (y * s.wi.y.max(0.0) / s.pdf) as f64
            })
        })
        .sum();
    sum / n as f64
}

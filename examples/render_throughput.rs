//! Renders the point-light-over-plane scene (or the default scene with `default`) at 128x128 and
//! 64 spp several times and prints camera samples per second and the time of each pass: a quick
//! loop for profiling.
//! `cargo run --release --example render_throughput [default] [repeats]`

use bevy_ecs::prelude::*;
use kelvin::render::renderer::{RenderOptions, Strategy, render};
use kelvin::systems::LightingPlugin;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let default = args.iter().any(|a| a == "default");
    let repeats: usize = args.iter().find_map(|a| a.parse().ok()).unwrap_or(5);
    let mut world = World::new();
    let mut schedule = Schedule::default();
    LightingPlugin::build(&mut world, &mut schedule);
    if default {
        kelvin::scenes::default_scene::spawn_default_scene(&mut world);
    } else {
        kelvin::scenes::bench_scenes::spawn_point_over_plane(&mut world);
    }
    let opts = RenderOptions { width: 128, height: 128, spp: 64, strategy: Strategy::Mis, crop: None };
    for _ in 0..repeats {
        let (_, stats) = render(&mut world, &mut schedule, &opts, |_| {});
        let p = stats.passes;
        println!(
            "{:.1} ms, {:.2} M samples/s, {:.2} M shadow rays/s (camera {:.2} ms, light system {:.2} ms, shading and film {:.2} ms)",
            stats.seconds * 1e3,
            stats.camera_samples as f64 / stats.seconds / 1e6,
            stats.shadow_rays as f64 / stats.seconds / 1e6,
            p.camera * 1e3,
            p.light_system * 1e3,
            p.shading * 1e3
        );
    }
}

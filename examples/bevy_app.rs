//! kelvin in a headless Bevy app: 1,000 point and spot lights circling over a floor, moved by
//! Bevy's `Transform` every frame, and 10,000 query points on a grid. Each frame prints the frame
//! time and the illuminance at a few points, the light system's estimate beside the closed form.
//!
//! `cargo run --release --example bevy_app --features bevy [FRAMES]`
//!
//! The app's plugins are what Bevy's `MinimalPlugins` brings that matters here (`TaskPoolPlugin`;
//! frames are stepped by `App::update` instead of a runner), plus `TransformPlugin` for
//! propagation: the `bevy` umbrella crate 0.20 needs a newer Rust than kelvin's 1.95.

use std::f32::consts::TAU;
use std::time::Instant;

use bevy_app::{App, TaskPoolPlugin, Update};
use bevy_ecs::prelude::*;
use bevy_math::Dir3;
use bevy_transform::TransformPlugin;
use bevy_transform::components::{GlobalTransform, Transform};
use glam::Vec3;
use kelvin::geometry::Placement;
use kelvin::light::{Amount, PointLight, SpotLight};
use kelvin::prelude::{DirectLighting, LightSamplerKind, LightingPlugin, Settings, ShadingBatch};
use kelvin::shading::LightSelection;
use kelvin::spectrum::Spectrum;

/// What the demo spawns and how the light system samples it.
#[derive(Clone, Debug)]
pub struct Demo {
    /// Lights, half point and half spot.
    pub lights: usize,
    /// Query points per side of the floor grid (`grid * grid` points).
    pub grid: usize,
    /// One sampled light per point (the light BVH), or every light.
    pub selection: LightSelection,
    /// Light samples per point per frame.
    pub samples_per_point: u32,
}

impl Default for Demo {
    fn default() -> Self {
        Self { lights: 1_000, grid: 100, selection: LightSelection::OneSampled, samples_per_point: 4 }
    }
}

/// Side of the square floor, m.
pub const FLOOR: f32 = 40.0;

/// A light's circle above the floor: it turns `speed` radians per frame.
#[derive(Component, Clone, Copy, Debug)]
pub struct Orbit {
    pub center: Vec3,
    pub radius: f32,
    pub speed: f32,
    pub phase: f32,
}

/// Frames stepped so far.
#[derive(Resource, Default)]
pub struct FrameCount(pub u32);

/// The app, its lights spawned and its query points in the `ShadingBatch`.
pub fn app(demo: &Demo) -> App {
    let mut app = App::new();
    app.add_plugins((TaskPoolPlugin::default(), TransformPlugin, LightingPlugin::default()));
    app.insert_resource(Settings {
        light_sampler: LightSamplerKind::Bvh,
        selection: demo.selection,
        samples_per_point: demo.samples_per_point,
        ..Default::default()
    });
    app.init_resource::<FrameCount>();
    app.add_systems(Update, move_lights);

    let world = app.world_mut();
    // A fixed-seed scatter (splitmix-style hash), so every run and every test sees the same scene.
    let hash = |i: usize, k: u64| {
        let mut z = (i as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ k.wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 31)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 29)) >> 40) as f32 / (1u64 << 24) as f32
    };
    for i in 0..demo.lights {
        let orbit = Orbit {
            center: Vec3::new((hash(i, 1) - 0.5) * FLOOR, 2.0 + 4.0 * hash(i, 2), (hash(i, 3) - 0.5) * FLOOR),
            radius: 0.5 + 2.0 * hash(i, 4),
            speed: 0.01 + 0.05 * hash(i, 5),
            phase: TAU * hash(i, 6),
        };
        let spectrum = Spectrum::blackbody(f64::from(2700.0 + 3800.0 * hash(i, 7))).expect("blackbody in range");
        let candela = 20.0 + 180.0 * hash(i, 8);
        let transform = Transform::from_translation(to_bevy(position(&orbit, 0)));
        if i % 2 == 0 {
            world.spawn((
                PointLight { amount: Amount::Candela(candela), spectrum, ..Default::default() },
                transform,
                orbit,
            ));
        } else {
            let spot = SpotLight {
                amount: Amount::Candela(candela),
                spectrum,
                inner_angle: 0.3,
                outer_angle: 0.6,
                ..Default::default()
            };
            world.spawn((spot, transform.looking_to(Dir3::NEG_Y, Dir3::Z), orbit));
        }
    }
    let mut batch = world.resource_mut::<ShadingBatch>();
    batch.clear();
    for (k, p) in grid_points(demo.grid).into_iter().enumerate() {
        batch.push(p, Vec3::Y, k as u32, 0);
    }
    app
}

/// The query points: a `grid` x `grid` lattice over the floor, facing up.
pub fn grid_points(grid: usize) -> Vec<Vec3> {
    let step = FLOOR / grid as f32;
    let at = |i: usize| -0.5 * FLOOR + (i as f32 + 0.5) * step;
    (0..grid * grid).map(|k| Vec3::new(at(k % grid), 0.0, at(k / grid))).collect()
}

/// Where a light on `orbit` is at frame `frame`.
pub fn position(orbit: &Orbit, frame: u32) -> Vec3 {
    let a = orbit.phase + orbit.speed * frame as f32;
    orbit.center + orbit.radius * Vec3::new(a.cos(), 0.0, a.sin())
}

/// Bevy's math is another glam version than kelvin's: vectors cross as plain floats.
pub fn to_bevy(v: Vec3) -> bevy_math::Vec3 {
    bevy_math::Vec3::from_array(v.to_array())
}

/// Moves every light to its place on its orbit for the next frame, and gives the frame its own
/// random numbers (the light system's are keyed by seed, point and sample).
fn move_lights(
    mut frame: ResMut<FrameCount>,
    mut settings: ResMut<Settings>,
    mut lights: Query<(&Orbit, &mut Transform)>,
) {
    frame.0 += 1;
    settings.seed = u64::from(frame.0);
    for (orbit, mut transform) in &mut lights {
        transform.translation = to_bevy(position(orbit, frame.0));
    }
}

/// The light system's illuminance estimate (lx) at query point `i` with normal `n`: the sum over
/// its entries of Y(Li) cos(theta) / pdf (each pdf carries the samples per point).
pub fn estimated_lux(lighting: &DirectLighting, i: usize, n: Vec3) -> f32 {
    let li = lighting.irradiance(i, n).0;
    // Luminance of photometric linear sRGB (ITU-R BT.709 Y row).
    0.2126 * li[0] + 0.7152 * li[1] + 0.0722 * li[2]
}

/// The closed form (lx) at `p` with normal `n`: the sum over lights of I falloff cos(theta) / d^2,
/// with I in candela and each light where its `GlobalTransform` puts it.
pub fn exact_lux(world: &mut World, p: Vec3, n: Vec3) -> f32 {
    let lux = |i: f32, at: Vec3, falloff: f32| {
        let d = at - p;
        i * falloff * n.dot(d.normalize()).max(0.0) / d.length_squared()
    };
    let points: f32 = world
        .query::<(&PointLight, &GlobalTransform)>()
        .iter(world)
        .map(|(l, g)| match l.amount {
            Amount::Candela(i) => lux(i, g.placement().translation, 1.0),
            _ => unreachable!("the demo's lights are given in candela"),
        })
        .sum();
    let spots: f32 = world
        .query::<(&SpotLight, &GlobalTransform)>()
        .iter(world)
        .map(|(l, g)| {
            let t = g.placement();
            let falloff = l.resolve(&t).expect("valid spot").falloff((p - t.translation).normalize());
            match l.amount {
                Amount::Candela(i) => lux(i, t.translation, falloff),
                _ => unreachable!("the demo's lights are given in candela"),
            }
        })
        .sum();
    points + spots
}

#[allow(dead_code)] // the test includes this file for its functions, not for main
fn main() {
    let frames: u32 = std::env::args().nth(1).and_then(|a| a.parse().ok()).unwrap_or(60);
    let demo = Demo::default();
    let mut app = app(&demo);
    let points = grid_points(demo.grid);
    let probes = [0, points.len() / 2 + demo.grid / 2, points.len() - 1];
    println!(
        "{} lights ({} point, {} spot), {} query points, light BVH, {} samples per point",
        demo.lights,
        demo.lights.div_ceil(2),
        demo.lights / 2,
        points.len(),
        demo.samples_per_point
    );
    let mut total = 0.0;
    for frame in 1..=frames {
        let t = Instant::now();
        app.update();
        let ms = t.elapsed().as_secs_f64() * 1e3;
        total += ms;
        let world = app.world_mut();
        let mut line = format!("frame {frame:3}: {ms:6.2} ms");
        for &k in &probes {
            let estimate = estimated_lux(world.resource::<DirectLighting>(), k, Vec3::Y);
            let exact = exact_lux(world, points[k], Vec3::Y);
            line += &format!("  | point {k}: {estimate:7.2} lx (exact {exact:7.2})");
        }
        println!("{line}");
    }
    println!("mean frame time {:.2} ms over {frames} frames", total / f64::from(frames));
}

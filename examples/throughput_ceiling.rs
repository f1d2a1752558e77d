//! The ceiling for the throughput target: the point-light-over-plane scene of `render_throughput`
//! (128x128, 64 spp) rendered by a kernel hard-coded for it. It has one plane, one point light, a
//! Lambertian floor and a shadow ray against the plane. There is no BVH, no material, no light
//! selection and no batching. A general renderer does this work per sample and more, so in the
//! same form (scalar, or the same vector width) it does not beat these rates on the same machine.
//!
//! Two forms of the same arithmetic run: one sample at a time (scalar), and 16 samples at a time in
//! branch-free lanes that the compiler can vectorise. Compare the default build with
//! `RUSTFLAGS="-C target-cpu=native"` (AVX-512 where the CPU has it).
//! The same scene through kelvin's renderer is timed first, and its mean luminance shows that the
//! kernels compute the same image.
//! `cargo run --release --example throughput_ceiling [repeats]`

use bevy_ecs::prelude::*;
use glam::Vec3;
use kelvin::render::renderer::{RenderOptions, render};
use kelvin::rng::{Pattern, SampleStream};
use rayon::prelude::*;

const WIDTH: usize = 128;
const HEIGHT: usize = 128;
const SPP: usize = 64;
/// Samples per vector step.
const LANES: usize = 16;

/// The sum of one pixel's samples.
type PixelKernel = fn(&Scene, usize) -> f64;

/// The scene and camera of `bench_scenes::spawn_point_over_plane`, in the form the kernels use.
struct Scene {
    eye: Vec3,
    corner: Vec3,
    per_x: Vec3,
    per_y: Vec3,
    light: Vec3,
    /// Intensity (cd) times albedo / pi.
    scaled_intensity: f32,
}

impl Scene {
    fn new() -> Self {
        let eye = Vec3::new(0.0, 3.0, 4.0);
        let forward = (-eye).normalize();
        let right = forward.cross(Vec3::Y).normalize();
        let up = right.cross(forward);
        let step = 2.0 * 25f32.to_radians().tan() / HEIGHT as f32;
        let (per_x, per_y) = (right * step, -up * step);
        let corner = forward - per_x * (WIDTH as f32 / 2.0) - per_y * (HEIGHT as f32 / 2.0);
        let light = Vec3::new(0.0, 2.0, 0.0);
        Self { eye, corner, per_x, per_y, light, scaled_intensity: 100.0 * 0.5 / std::f32::consts::PI }
    }

    /// Radiance of one camera ray through film position (`fx`, `fy`): the plane y = 0
    /// (|x|, |z| <= 10) lit by the point light, with a shadow ray against the plane.
    #[inline(always)]
    fn radiance(&self, fx: f32, fy: f32) -> f32 {
        let d = (self.corner + self.per_x * fx + self.per_y * fy).normalize();
        let t = -self.eye.y / d.y;
        let (px, pz) = (self.eye.x + t * d.x, self.eye.z + t * d.z);
        let on_floor = d.y < 0.0 && px.abs() <= 10.0 && pz.abs() <= 10.0;
        // The hit lies on y = 0; its shadow ray leaves from just above, toward the light.
        let origin_y = (px.abs().max(pz.abs()) * 1.2e-7).max(1e-7);
        let t_shadow = -origin_y / (self.light.y - origin_y);
        let blocked = t_shadow > 0.0 && t_shadow < 0.999;
        let (lx, ly, lz) = (self.light.x - px, self.light.y, self.light.z - pz);
        let r2 = lx * lx + ly * ly + lz * lz;
        let cos = (ly / r2.sqrt()).max(0.0);
        if on_floor && !blocked { self.scaled_intensity * cos / r2 } else { 0.0 }
    }

    /// The random film offsets of `pixel`'s `sample` (the renderer's counter-based stream).
    #[inline(always)]
    fn film_position(pixel: usize, sample: usize) -> (f32, f32) {
        let u = SampleStream::new(Pattern::Sobol, 0, pixel as u32, sample as u32).at_dimension(1).next_2d();
        ((pixel % WIDTH) as f32 + u.x, (pixel / WIDTH) as f32 + u.y)
    }

    /// Sum of one pixel's samples, one at a time.
    fn pixel_scalar(&self, pixel: usize) -> f64 {
        (0..SPP)
            .map(|s| {
                let (fx, fy) = Self::film_position(pixel, s);
                self.radiance(fx, fy) as f64
            })
            .sum()
    }

    /// Sum of one pixel's samples, `LANES` at a time: film positions first, then the same
    /// radiance over arrays, which the compiler turns into vector code.
    fn pixel_lanes(&self, pixel: usize) -> f64 {
        let mut total = 0.0;
        for first in (0..SPP).step_by(LANES) {
            let (mut fx, mut fy) = ([0.0f32; LANES], [0.0f32; LANES]);
            for l in 0..LANES {
                (fx[l], fy[l]) = Self::film_position(pixel, first + l);
            }
            let values: [f32; LANES] = std::array::from_fn(|l| self.radiance(fx[l], fy[l]));
            total += values.iter().map(|&v| v as f64).sum::<f64>();
        }
        total
    }
}

fn main() {
    let repeats: usize = std::env::args().skip(1).find_map(|a| a.parse().ok()).unwrap_or(6);
    let total = (WIDTH * HEIGHT * SPP) as f64;
    let (mut world, mut schedule) = (World::new(), Schedule::default());
    kelvin::systems::LightingPlugin::build(&mut world, &mut schedule);
    kelvin::scenes::bench_scenes::spawn_point_over_plane(&mut world);
    let opts = RenderOptions::direct(WIDTH as u32, HEIGHT as u32, SPP as u32);
    let mut best = f64::INFINITY;
    let mut pixels = Vec::new();
    for _ in 0..repeats {
        let (film, stats) = render(&mut world, &mut schedule, &opts, |_| {});
        (best, pixels) = (best.min(stats.seconds), film.pixels());
    }
    let mean =
        pixels.iter().map(|p| p.dot(Vec3::new(0.2126, 0.7152, 0.0722)) as f64).sum::<f64>() / pixels.len() as f64;
    println!(
        "  kelvin: {:.2} ms, {:.1} M samples/s (best of {repeats}); mean luminance {mean:.6}",
        best * 1e3,
        total / best / 1e6
    );

    let scene = Scene::new();
    let kernels: [(&str, PixelKernel); 2] = [("scalar", Scene::pixel_scalar), ("16 lanes", Scene::pixel_lanes)];
    for (name, kernel) in kernels {
        let mut best = f64::INFINITY;
        let mut film = vec![0.0f64; WIDTH * HEIGHT];
        for _ in 0..repeats {
            let start = std::time::Instant::now();
            film.par_iter_mut().enumerate().with_min_len(4).for_each(|(pixel, sum)| *sum = kernel(&scene, pixel));
            best = best.min(start.elapsed().as_secs_f64());
        }
        let (mean, rate) = (film.iter().sum::<f64>() / total, total / best / 1e6);
        println!(
            "{name:>8}: {:.2} ms, {rate:.1} M samples/s (best of {repeats}); mean luminance {mean:.6}",
            best * 1e3
        );
    }
}

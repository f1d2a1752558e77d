//! A colour checker: 24 Lambertian patches with the sRGB colours of the X-Rite ColorChecker
//! Classic, lit by one distant light of a chosen spectrum and seen head-on. The accuracy report
//! renders it under a 2700 K blackbody and CIE F11 to price RGB rendering against spectral.

use bevy_ecs::prelude::*;
use glam::{Vec2, Vec3};

use crate::geometry::{Rectangle, Transform};
use crate::light::{Amount, DistantLight};
use crate::render::camera::Camera;
use crate::render::material::Material;
use crate::scene::image::srgb_decode;
use crate::spectrum::Spectrum;

/// The ColorChecker Classic's 24 patches in chart order (rows of six from dark skin to black)
/// as 8-bit sRGB: the values tabulated in Wikipedia's "ColorChecker" article from BabelColor's
/// averaged measurements (D. Pascale, "RGB coordinates of the Macbeth ColorChecker", 2006).
pub const COLOR_CHECKER_SRGB8: [(&str, [u8; 3]); 24] = [
    ("dark skin", [115, 82, 68]),
    ("light skin", [194, 150, 130]),
    ("blue sky", [98, 122, 157]),
    ("foliage", [87, 108, 67]),
    ("blue flower", [133, 128, 177]),
    ("bluish green", [103, 189, 170]),
    ("orange", [214, 126, 44]),
    ("purplish blue", [80, 91, 166]),
    ("moderate red", [193, 90, 99]),
    ("purple", [94, 60, 108]),
    ("yellow green", [157, 188, 64]),
    ("orange yellow", [224, 163, 46]),
    ("blue", [56, 61, 150]),
    ("green", [70, 148, 73]),
    ("red", [175, 54, 60]),
    ("yellow", [231, 199, 31]),
    ("magenta", [187, 86, 149]),
    ("cyan", [8, 133, 161]),
    ("white 9.5", [243, 243, 242]),
    ("neutral 8", [200, 200, 200]),
    ("neutral 6.5", [160, 160, 160]),
    ("neutral 5", [122, 122, 121]),
    ("neutral 3.5", [85, 85, 85]),
    ("black 2", [52, 52, 52]),
];

/// Patch side and pitch, m (the real chart: 40 mm patches; this one is 2.5 x larger).
const PATCH: f32 = 0.1;
const PITCH: f32 = 0.12;
/// Illuminance on a surface facing the light, lx.
const LUX: f32 = 1000.0;
/// Camera distance from the chart and half the height it sees, m.
const EYE_DISTANCE: f32 = 2.0;
const HALF_VIEW: f32 = 0.4;

/// One patch: its name, linear-sRGB albedo and centre on the chart plane (z = 0).
#[derive(Clone, Debug, PartialEq)]
pub struct Patch {
    /// The patch's name on the chart.
    pub name: &'static str,
    /// Its albedo, linear sRGB.
    pub albedo: Vec3,
    /// Its centre on the chart, metres.
    pub center: Vec2,
}

/// What [`spawn_color_checker`] made: the patches and how to find them in the image.
#[derive(Clone, Debug, PartialEq)]
pub struct ColorChecker {
    /// The chart's patches.
    pub patches: Vec<Patch>,
    /// Luminance of a perfect white Lambertian surface on the chart, cd/m^2: the white of
    /// CIELAB comparisons (E cos(theta) / pi).
    pub white_luminance: f32,
}

impl ColorChecker {
    /// The central half (per axis) of patch `i` in a `width` x `height` image of the chart, as
    /// pixel ranges `[x0, x1) x [y0, y1)` (at least one pixel each).
    pub fn patch_pixels(&self, i: usize, width: u32, height: u32) -> ([u32; 2], [u32; 2]) {
        let aspect = width as f32 / height as f32;
        let c = self.patches[i].center;
        let half = 0.25 * PATCH;
        // The camera looks along -Z from z = EYE_DISTANCE with +Y up; the chart is at z = 0.
        let to_px = |x: f32| (x / (HALF_VIEW * aspect) + 1.0) * 0.5 * width as f32;
        let to_py = |y: f32| (1.0 - y / HALF_VIEW) * 0.5 * height as f32;
        let range = |a: f32, b: f32, n: u32| {
            let (lo, hi) = (a.min(b).ceil().max(0.0) as u32, (a.max(b).floor() as u32).min(n));
            if hi > lo { [lo, hi] } else { [lo.min(n - 1), lo.min(n - 1) + 1] }
        };
        (range(to_px(c.x - half), to_px(c.x + half), width), range(to_py(c.y + half), to_py(c.y - half), height))
    }
}

/// Spawns the chart (24 patches on a dark board at z = 0, facing +Z), a distant light of
/// `spectrum` giving 1000 lx from above and in front, and a camera looking at the chart.
pub fn spawn_color_checker(world: &mut World, spectrum: Spectrum) -> ColorChecker {
    let facing_z = Transform::default(); // a Rectangle's front is its local +Z
    let board = Rectangle { half_size: Vec2::new(3.0 * PITCH + 0.05, 2.0 * PITCH + 0.05) };
    world.spawn((
        board,
        Transform::from_translation(Vec3::new(0.0, 0.0, -0.005)),
        Material::lambertian(Vec3::splat(0.03)),
    ));
    let patches: Vec<Patch> = COLOR_CHECKER_SRGB8
        .iter()
        .enumerate()
        .map(|(i, (name, rgb8))| {
            let (col, row) = ((i % 6) as f32, (i / 6) as f32);
            let center = Vec2::new((col - 2.5) * PITCH, (1.5 - row) * PITCH);
            let albedo = Vec3::from_array(rgb8.map(|v| srgb_decode(v as f64 / 255.0) as f32));
            Patch { name, albedo, center }
        })
        .collect();
    for p in &patches {
        let t = Transform { translation: p.center.extend(0.0), ..facing_z };
        world.spawn((Rectangle { half_size: Vec2::splat(0.5 * PATCH) }, t, Material::lambertian(p.albedo)));
    }
    // Light travelling down and into the chart, 30 degrees off its normal.
    let travel = Vec3::new(0.0, -0.5, -(0.75f32).sqrt());
    let light = DistantLight { amount: Amount::Lux(LUX), spectrum, ..Default::default() };
    world.spawn((light, Transform::default().looking_to(travel, Vec3::Y)));
    let yfov = 2.0 * (HALF_VIEW / EYE_DISTANCE).atan();
    let eye = Transform::from_translation(Vec3::new(0.0, 0.0, EYE_DISTANCE)).looking_to(Vec3::NEG_Z, Vec3::Y);
    world.spawn((Camera { yfov }, eye));
    ColorChecker { patches, white_luminance: LUX * (-travel.z) / std::f32::consts::PI }
}

//! A crop renders the same region of the full image bit for bit (same camera rays, same per-pixel
//! random streams), in RGB and spectral modes, for crops aligned to nothing: not to rows, lane
//! blocks, pixel groups or batches.

mod common;

use bevy_ecs::prelude::*;
use glam::Vec3;
use kelvin::render::renderer::{Integrator, RenderOptions, render};
use kelvin::render::tiles::{Crop, Tile, merge_tiles};
use kelvin::shading::{ColorMode, LightSamplerKind, LightSelection, Restir, Settings};
use kelvin::systems::LightingPlugin;

/// A world with `scene` (None: the default scene) in the given colour mode.
fn world(scene: Option<&str>, color_mode: ColorMode) -> (World, Schedule) {
    world_with(scene, Settings { color_mode, seed: 3, ..Default::default() })
}

fn world_with(scene: Option<&str>, settings: Settings) -> (World, Schedule) {
    let mut world = World::new();
    let mut schedule = Schedule::default();
    world.insert_resource(settings);
    LightingPlugin::build(&mut world, &mut schedule);
    match scene {
        Some(rel) => {
            kelvin::render::scene_file::spawn_gltf_file(&mut world, &common::files::test_data(rel)).unwrap();
        }
        None => kelvin::scenes::default_scene::spawn_default_scene(&mut world),
    }
    (world, schedule)
}

fn pixels(scene: Option<&str>, color_mode: ColorMode, opts: &RenderOptions) -> (u32, u32, Vec<Vec3>) {
    let (mut world, mut schedule) = world(scene, color_mode);
    let (film, _) = render(&mut world, &mut schedule, opts, |_| {});
    (film.width, film.height, film.pixels())
}

fn region_of(full: &[Vec3], width: u32, crop: Crop) -> Vec<Vec3> {
    let rows = (crop.y0..crop.y1).map(|y| y as usize * width as usize);
    rows.flat_map(|r| full[r + crop.x0 as usize..r + crop.x1 as usize].to_vec()).collect()
}

fn bits(v: &[Vec3]) -> Vec<[u32; 3]> {
    v.iter().map(|p| p.to_array().map(f32::to_bits)).collect()
}

#[test]
fn crops_equal_the_full_render_bit_for_bit_in_rgb_and_spectral_mode() {
    // 67 x 53 x 5 spp = 17755 samples: the full render takes two batches; spp 20 puts a pixel's
    // samples across lane blocks.
    let crops = [Crop { x0: 3, y0: 5, x1: 44, y1: 50 }, Crop { x0: 61, y0: 0, x1: 67, y1: 1 }];
    // The path tracer (the default) on the default scene, direct lighting on the Cornell box.
    let cases = [(None, 5, Integrator::default()), (Some("gltf/bevy/CornellBox.glb"), 20, Integrator::Direct)];
    for (scene, spp, integrator) in cases {
        for mode in [ColorMode::Rgb, ColorMode::Spectral] {
            let opts = RenderOptions { width: 67, height: 53, spp, integrator, ..Default::default() };
            let (w, _, full) = pixels(scene, mode, &opts);
            for crop in crops {
                let (cw, ch, tile) = pixels(scene, mode, &RenderOptions { crop: Some(crop), ..opts.clone() });
                assert_eq!((cw, ch), (crop.width(), crop.height()));
                let expected = region_of(&full, w, crop);
                let lit = expected.iter().filter(|p| **p != Vec3::ZERO).count();
                assert!(crop != crops[0] || lit > 100, "{scene:?} {mode:?}: the region is lit");
                assert!(bits(&tile) == bits(&expected), "{scene:?} {mode:?} crop {crop}: pixels differ");
            }
        }
    }
}

/// Tiles of a 4 x 3 grid with uneven edges merge into the full render exactly.
#[test]
fn a_grid_of_tiles_merges_into_the_full_render() {
    let opts = RenderOptions { width: 29, height: 17, spp: 3, ..Default::default() };
    let (_, _, full) = pixels(None, ColorMode::Rgb, &opts);
    let (xs, ys) = ([0, 7, 8, 20, 29], [0, 5, 16, 17]);
    let mut tiles = Vec::new();
    for y in ys.windows(2) {
        for x in xs.windows(2) {
            let crop = Crop::new(x[0], y[0], x[1], y[1]).unwrap();
            let (_, _, pixels) = pixels(None, ColorMode::Rgb, &RenderOptions { crop: Some(crop), ..opts.clone() });
            tiles.push(Tile { name: format!("tile {crop}"), width: 29, height: 17, crop, pixels });
        }
    }
    let (w, h, merged) = merge_tiles(&tiles).unwrap();
    assert_eq!((w, h), (29, 17));
    assert!(bits(&merged) == bits(&full));
}

/// A crop partly outside the image renders the part inside; one wholly outside, an empty film.
#[test]
fn crops_are_clipped_to_the_image_without_panicking() {
    let opts = RenderOptions { width: 10, height: 8, spp: 1, ..Default::default() };
    let (_, _, full) = pixels(None, ColorMode::Rgb, &opts);
    let partly = Crop { x0: 6, y0: 4, x1: 20, y1: 20 };
    assert!(partly.check(10, 8).is_err());
    let (w, h, tile) = pixels(None, ColorMode::Rgb, &RenderOptions { crop: Some(partly), ..opts.clone() });
    assert_eq!((w, h), (4, 4));
    assert!(bits(&tile) == bits(&region_of(&full, 10, Crop { x0: 6, y0: 4, x1: 10, y1: 8 })));
    let outside = Crop { x0: 12, y0: 0, x1: 20, y1: 3 };
    let (w, h, tile) = pixels(None, ColorMode::Rgb, &RenderOptions { crop: Some(outside), ..opts });
    assert_eq!((w * h, tile.len()), (0, 0));
}

/// The renderling scene's four point lights, with area lights and an image light added: a disk
/// over the cubes, a textured rectangle beside them (its texture varies over it, so a sample's
/// texel matters) and a lat-long sky with a hot spot, so that crops go through every light's
/// sampling and evaluation code, not the point lights' alone.
fn every_kind_of_light(world: &mut World) {
    use kelvin::geometry::{Disk, Rectangle, Transform};
    use kelvin::light::{Amount, AreaLight, ImageInfiniteLight, LightTexture};
    use std::sync::Arc;
    let down = Transform::from_translation(Vec3::new(0.0, 4.0, 0.0)).looking_to(Vec3::NEG_Y, Vec3::Z);
    let disk = AreaLight { amount: Amount::Nits(2000.0), ..Default::default() };
    world.spawn((Disk { radius: 1.5, inner_radius: 0.0 }, down, disk));
    let texels = (0..12).map(|i| Vec3::new(0.2 + 0.3 * (i % 4) as f32, 1.0, 0.1 * (i / 4) as f32)).collect();
    let texture = Arc::new(LightTexture::new(4, 3, texels).unwrap());
    let panel =
        AreaLight { amount: Amount::Nits(3000.0), texture: Some(texture), two_sided: true, ..Default::default() };
    let beside = Transform::from_translation(Vec3::new(6.0, 1.0, 0.0)).looking_to(Vec3::NEG_X, Vec3::Y);
    world.spawn((Rectangle { half_size: glam::Vec2::new(1.0, 2.0) }, beside, panel));
    let (width, height) = (32usize, 16usize);
    let pixels = (0..width * height)
        .map(
            |i| if i == 3 * width + 5 { Vec3::new(9000.0, 8000.0, 6000.0) } else { Vec3::splat(20.0 + (i % 7) as f32) },
        )
        .collect();
    let sky = kelvin::scene::image::RgbImage { width, height, pixels };
    world.spawn((ImageInfiniteLight::new(Arc::new(sky)), Transform::IDENTITY));
}

/// Every light sampler and selection that tiles (uniform, power, BVH, all lights, RIS, ReSTIR
/// with 0 neighbours with and without temporal reuse) gives crops equal to the full render bit
/// for bit, through both integrators, on a scene of point, area (disk and textured rectangle)
/// and image lights.
#[test]
fn crops_equal_the_full_render_for_every_light_sampler() {
    let kinds = [LightSamplerKind::Uniform, LightSamplerKind::Power, LightSamplerKind::Bvh];
    let mut cases: Vec<(LightSamplerKind, LightSelection)> =
        kinds.iter().map(|&k| (k, LightSelection::OneSampled)).collect();
    cases.push((LightSamplerKind::Bvh, LightSelection::All));
    cases.push((LightSamplerKind::Bvh, LightSelection::Resampled { candidates: 4 }));
    for temporal in [false, true] {
        let restir = Restir { candidates: 4, spatial: 0, temporal, ..Restir::default() };
        cases.push((LightSamplerKind::Bvh, LightSelection::Restir(restir)));
    }
    let crop = Crop { x0: 5, y0: 3, x1: 30, y1: 19 };
    let scene = Some("gltf/renderling/shadow_mapping_points.glb");
    for (light_sampler, selection) in cases {
        for integrator in [Integrator::Direct, Integrator::default()] {
            let settings = Settings { light_sampler, selection, seed: 11, ..Default::default() };
            let opts = RenderOptions { width: 37, height: 23, spp: 4, integrator, ..Default::default() };
            assert!(opts.check_tiling(&selection).is_ok());
            let render = |opts: &RenderOptions| {
                let (mut world, mut schedule) = world_with(scene, settings.clone());
                every_kind_of_light(&mut world);
                let (film, stats) = render(&mut world, &mut schedule, opts, |_| {});
                assert!(stats.report.warnings.is_empty(), "{:?}", stats.report.warnings);
                film.pixels()
            };
            let full = render(&opts);
            let tile = render(&RenderOptions { crop: Some(crop), ..opts.clone() });
            let expected = region_of(&full, 37, crop);
            assert!(expected.iter().filter(|p| **p != Vec3::ZERO).count() > 100, "{light_sampler:?} {selection:?}");
            let differ = bits(&tile).iter().zip(bits(&expected)).filter(|(a, b)| **a != *b).count();
            assert!(differ == 0, "{light_sampler:?} {selection:?} {integrator:?}: {differ} pixels differ");
        }
    }
}

/// Hard case: ReSTIR's spatial reuse takes neighbours from the render's own samples, so a tile is
/// another image (measured: it differs from the full render's region); a time budget gives tiles
/// different sample counts. Both are refused by `check_tiling` and warned about by a render; a
/// crop of the whole image is the full render and is accepted. Temporal reuse alone is accepted
/// (a render gives no previous points; the crops above are bit-identical with it), with spatial
/// reuse still refused.
#[test]
fn restir_and_time_budgets_refuse_to_tile() {
    let restir = LightSelection::Restir(Restir { spatial: 4, radius: 8, temporal: false, ..Restir::default() });
    let opts = RenderOptions { width: 37, height: 23, spp: 4, integrator: Integrator::Direct, ..Default::default() };
    let crop = Crop { x0: 5, y0: 3, x1: 30, y1: 19 };
    let tiled = RenderOptions { crop: Some(crop), ..opts.clone() };
    assert!(tiled.check_tiling(&restir).is_err_and(|e| e.to_string().contains("ReSTIR")));
    let both = LightSelection::Restir(Restir { spatial: 4, radius: 8, temporal: true, ..Restir::default() });
    assert!(tiled.check_tiling(&both).is_err_and(|e| e.to_string().contains("spatial reuse")));
    let temporal_only = LightSelection::Restir(Restir { spatial: 0, temporal: true, ..Restir::default() });
    assert!(tiled.check_tiling(&temporal_only).is_ok());
    let whole = RenderOptions { crop: Some(Crop::full(37, 23)), ..opts.clone() };
    assert!(whole.check_tiling(&restir).is_ok());
    let timed = RenderOptions { time_budget: Some(std::time::Duration::from_millis(1)), ..tiled.clone() };
    assert!(timed.check_tiling(&LightSelection::OneSampled).is_err_and(|e| e.to_string().contains("time budget")));

    let settings = Settings { selection: restir, seed: 11, ..Default::default() };
    let scene = Some("gltf/renderling/shadow_mapping_points.glb");
    let (mut world, mut schedule) = world_with(scene, settings.clone());
    let full = render(&mut world, &mut schedule, &opts, |_| {}).0.pixels();
    let (mut world, mut schedule) = world_with(scene, settings);
    let (film, stats) = render(&mut world, &mut schedule, &tiled, |_| {});
    assert!(bits(&film.pixels()) != bits(&region_of(&full, 37, crop)), "the refusal has a reason");
    assert!(stats.report.warnings.iter().any(|w| w.contains("ReSTIR")), "{:?}", stats.report.warnings);
}

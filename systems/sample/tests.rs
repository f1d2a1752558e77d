//! Tests of the sampling pass: lane paths against the one-at-a-time path, slots with no point.

use super::*;
use crate::geometry::Transform;
use crate::lanes::Vec3x16;
use crate::light::{Amount, DistantLight, PointLight, SpotLight, UniformInfiniteLight};
use crate::rng::SplitMix64;

/// A slot with no point (a non-finite position: an escaped camera ray) gets empty entries
/// and no shadow rays under every selection, even from lights whose samples ignore the
/// point (a uniform sky, a distant light).
#[test]
fn slot_without_point_gets_no_light() {
    for selection in [LightSelection::OneSampled, LightSelection::All] {
        let mut world = World::new();
        let mut schedule = Schedule::default();
        world.insert_resource(Settings { selection, samples_per_point: 2, ..Default::default() });
        crate::systems::LightingPlugin::build(&mut world, &mut schedule);
        world.resource_mut::<ShadowRays>().keep = true;
        world.spawn((UniformInfiniteLight::default(), Transform::default()));
        world.spawn((DistantLight { amount: Amount::Lux(1.0), ..Default::default() }, Transform::default()));
        world.spawn((PointLight::candela(10.0), Transform::from_translation(Vec3::Y)));
        {
            let mut batch = world.resource_mut::<ShadingBatch>();
            batch.push(Vec3::ZERO, Vec3::Y, 0, 0);
            batch.push(Vec3::new(f32::NAN, 0.0, 0.0), Vec3::ZERO, 1, 0);
            batch.push(Vec3::new(0.0, f32::INFINITY, 0.0), Vec3::ZERO, 2, 0);
        }
        schedule.run(&mut world);
        let (lit, rays) = (world.resource::<DirectLighting>(), world.resource::<ShadowRays>());
        assert!(lit.entries(0).any(|e| lit.pdf[e] > 0.0), "{selection:?}: the real point is lit");
        for e in lit.entries(1).chain(lit.entries(2)) {
            assert_eq!((lit.pdf[e], lit.radiance[e], lit.light[e]), (0.0, SampledSpectrum::default(), NO_LIGHT));
            assert_eq!(rays.kind[e], ShadowTarget::None, "{selection:?}");
        }
    }
}

/// Entries the schedule wrote (through the lane path: one sampled or resampled light, RGB, f32) must equal
/// those of the one-at-a-time path, bit for bit, for a mix of light kinds, under the power,
/// uniform and BVH samplers. Hard cases: a point exactly at a light, one 1e-30 m from it
/// (r^2 underflows to 0), one 1e30 m away (r^2 overflows) and one at NaN (no light may be
/// chosen), plus a batch length that is no multiple of the lane count. With point lights
/// only, whole blocks go through the point kernel; one light (every lane the same row) and
/// three (rows differ between lanes) take its two ways of reading the light. With emissive
/// triangles only (a scene without point lights), blocks go through the triangle kernel: a large
/// triangle just above the points (solid-angle sampling; points within 1e-4 of its plane, which
/// the f32 bounds leave to the f64 reference) and a tiny far one (area sampling). With an image
/// light (alone, or among the mix), its lanes go through the image kernel: a turned map with a
/// sun and a black band, so that some sampled directions carry no radiance. The schedule runs
/// twice, on two orders of the points, so that a column the lane path fails to write keeps
/// the first run's value.
#[test]
fn lane_path_matches_entry_by_entry() {
    use crate::shading::LightSamplerKind::{Bvh, Power, Uniform};
    use crate::shading::LightSelection::{OneSampled, Resampled};
    // (samples per point, sampler, lights: 6 of four kinds with a disk light and an image light, 3
    // points, 1 point, 0: two emissive triangles, or 7: an image light alone; selection: one
    // sampled light, or resampled from candidates)
    let runs = [
        (1, Power, 6, OneSampled),
        (3, Power, 6, OneSampled),
        (2, Uniform, 6, OneSampled),
        (1, Bvh, 6, OneSampled),
        (1, Power, 3, OneSampled),
        (1, Power, 1, OneSampled),
        (2, Uniform, 1, OneSampled),
        (1, Bvh, 6, Resampled { candidates: 4 }),
        (2, Power, 6, Resampled { candidates: 3 }),
        (1, Uniform, 3, Resampled { candidates: 5 }),
        (1, Power, 0, OneSampled),
        (2, Bvh, 0, OneSampled),
        (1, Uniform, 0, Resampled { candidates: 4 }),
        (1, Power, 7, OneSampled),
        (2, Bvh, 7, OneSampled),
        (1, Uniform, 7, Resampled { candidates: 4 }),
    ];
    for (samples_per_point, light_sampler, lights, selection) in runs {
        let (points_only, triangles_only, mixed) = ((1..=3).contains(&lights), lights == 0, lights == 6);
        let sky_only = lights == 7;
        let no_points = triangles_only || sky_only;
        let mut world = World::new();
        let mut schedule = Schedule::default();
        crate::systems::LightingPlugin::build(&mut world, &mut schedule);
        let at = |x, y, z| Transform::from_translation(Vec3::new(x, y, z));
        if triangles_only {
            let big = [Vec3::new(-3.0, 2.5, -3.0), Vec3::new(3.0, 2.5, -3.0), Vec3::new(0.0, 2.5, 3.0)];
            // Beside the points, not above (the big one would shade it), and bright enough to be chosen.
            let tiny = big.map(|v| v * 0.01 + Vec3::new(30.0, 1.0, 20.0));
            for (triangle, nits) in [(big, 1e3), (tiny, 1e8)] {
                let mesh = crate::geometry::Mesh::from_triangles(&[triangle]).unwrap();
                let light =
                    crate::light::AreaLight { two_sided: true, amount: Amount::Nits(nits), ..Default::default() };
                world.spawn((light, mesh, at(0.0, 0.0, 0.0)));
            }
        } else if !sky_only {
            world.spawn((PointLight::candela(1e4), at(0.0, 2.0, 0.0)));
        }
        if mixed || sky_only {
            // A turned sky map with a sun and a black band (black radiance at some sampled directions).
            let (w, h) = (32, 16);
            let mut sky: Vec<Vec3> = (0..w * h).map(|i| Vec3::new(0.2, 0.3 + (i % w) as f32 * 0.02, 0.8)).collect();
            sky[4 * w + 9] = Vec3::splat(1e4);
            sky[10 * w..11 * w].fill(Vec3::ZERO);
            let image = std::sync::Arc::new(crate::scene::image::RgbImage { width: w, height: h, pixels: sky });
            let turn = Transform { rotation: glam::Quat::from_rotation_x(0.4), ..Transform::IDENTITY };
            world.spawn((crate::light::ImageInfiniteLight::new(image), turn));
        }
        if (2..=6).contains(&lights) {
            world.spawn((PointLight { casts_shadows: false, ..PointLight::candela(5e3) }, at(1.0, 1.0, 1.0)));
            world.spawn((PointLight::candela(3e3), at(-3.0, 0.5, 2.0)));
        }
        if mixed {
            let spot = SpotLight { amount: Amount::Candela(1e4), ..Default::default() };
            world.spawn((spot, at(0.0, 3.0, 0.0).looking_to(Vec3::NEG_Y, Vec3::Z)));
            world.spawn((DistantLight { amount: Amount::Lux(1.0), ..Default::default() }, Transform::default()));
            world.spawn((UniformInfiniteLight::default(), Transform::default()));
            // Samples on a surface: shadow rays that carry the light's normal.
            let disk = crate::geometry::Disk { radius: 0.5, inner_radius: 0.0 };
            let light = crate::light::AreaLight { two_sided: true, ..Default::default() };
            world.spawn((light, disk, at(2.0, 3.0, -1.0)));
        }
        // The segments are compared below.
        world.resource_mut::<ShadowRays>().keep = true;
        {
            let mut settings = world.resource_mut::<Settings>();
            (settings.samples_per_point, settings.light_sampler) = (samples_per_point, light_sampler);
            settings.selection = selection;
        }
        {
            let mut batch = world.resource_mut::<ShadingBatch>();
            batch.clear();
            // The hard cases sit in whole blocks of 16 in both orders.
            let mut rng = SplitMix64::new(3);
            for i in 3..201 {
                if i == 40 {
                    // At the light, in 4 samples: the power sampler picks that light in some.
                    for sample in 0..4 {
                        batch.push(Vec3::new(0.0, 2.0, 0.0), Vec3::Y, 0, sample);
                    }
                    batch.push(Vec3::new(0.0, 2.0 + 1e-30, 0.0), Vec3::Y, 1, 0);
                    batch.push(Vec3::new(1e30, 0.0, 0.0), Vec3::Y, 2, 0);
                    batch.push(Vec3::new(f32::NAN, 0.0, 0.0), Vec3::Y, 201, 0);
                }
                let p = Vec3::new(rng.f32() * 8.0 - 4.0, rng.f32() * 2.0, rng.f32() * 8.0 - 4.0);
                // Every seventh point within 1e-4 of the big triangle's plane (y = 2.5).
                let near_plane = triangles_only && i % 7 == 0;
                let p = if near_plane { Vec3::new(p.x * 0.5, 2.5 - 1e-4 * rng.f32(), p.z * 0.5) } else { p };
                batch.push(p, Vec3::Y, i, i % 5);
            }
        }
        schedule.run(&mut world);
        {
            let mut batch = world.resource_mut::<ShadingBatch>();
            batch.position.reverse();
            batch.pixel.reverse();
            batch.sample.reverse();
        }
        schedule.run(&mut world);
        let lit = world.resource::<DirectLighting>().clone();
        let rays = world.resource::<ShadowRays>().clone();

        let (batch, table, sampler, settings) = (
            world.resource::<ShadingBatch>(),
            world.resource::<LightTable>(),
            world.resource::<LightSampler>(),
            world.resource::<Settings>(),
        );
        let k = samples_per_point as usize;
        let sampling =
            Sampling { batch, table, sampler, settings, all_ids: &[], k, spp: samples_per_point, reservoirs: &[] };
        let m = batch.len() * k;
        let (mut radiance, mut wi, mut pdf) = (vec![SampledSpectrum::default(); m], vec![Vec3::ZERO; m], vec![0.0; m]);
        let (mut light, mut delta, mut occluded) = (vec![NO_LIGHT; m], vec![false; m], vec![true; m]);
        // Stale values the one-at-a-time path must overwrite, as the lane path must.
        let (mut ray_kind, mut target, mut target_normal) =
            (vec![ShadowTarget::None; m], vec![Vec3::splat(7.0); m], vec![Vec3::splat(7.0); m]);
        let mut cols = EntryColumns {
            radiance: &mut radiance,
            wi: &mut wi,
            pdf: &mut pdf,
            light: &mut light,
            delta: &mut delta,
            occluded: &mut occluded,
            ray_kind: &mut ray_kind,
            target: &mut target,
            target_normal: &mut target_normal,
            ray_occluded: None,
        };
        let traced: usize = (0..m).map(|e| sampling.entry(0, e, &mut cols) as usize).sum();
        assert_eq!(traced, rays.kind.iter().filter(|&&k| k != ShadowTarget::None).count());
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let vec_bits = |v: &[Vec3]| v.iter().flat_map(|x| x.to_array()).map(f32::to_bits).collect::<Vec<_>>();
        let spectrum_bits = |v: &[SampledSpectrum]| v.iter().flat_map(|x| x.0).map(f32::to_bits).collect::<Vec<_>>();
        // The schedule traced the shadow rays; the disk can block a sample of the skies.
        let blocked = lit.occluded.clone();
        assert!(selection != OneSampled || mixed || blocked.iter().all(|&b| !b), "no shadow falls on these samples");
        for e in (0..m).filter(|&e| blocked[e]) {
            radiance[e] = SampledSpectrum::default();
        }
        assert_eq!(spectrum_bits(&lit.radiance), spectrum_bits(&radiance));
        assert_eq!(vec_bits(&lit.wi), vec_bits(&wi));
        assert_eq!(bits(&lit.pdf), bits(&pdf));
        assert_eq!((&lit.light, &lit.delta), (&light, &delta));
        assert_eq!(rays.kind, ray_kind);
        // Targets are written for entries with rays only, normals for rays to a light's surface.
        let written = |column: &[Vec3], kinds: &[ShadowTarget]| {
            let entries = (0..m).filter(|&e| kinds.contains(&ray_kind[e]));
            vec_bits(&entries.map(|e| column[e]).collect::<Vec<_>>())
        };
        let rays_of_any_kind = [ShadowTarget::Point, ShadowTarget::Surface, ShadowTarget::Infinity];
        assert_eq!(written(&rays.target, &rays_of_any_kind), written(&target, &rays_of_any_kind));
        let surface = [ShadowTarget::Surface];
        assert_eq!(written(&rays.target_normal, &surface), written(&target_normal, &surface));
        // The mix reached every path: point lights in lanes, other kinds, failed samples.
        assert!(no_points || light.iter().any(|l| l.kind == LightKind::Point));
        assert!(points_only || light.iter().any(|l| l.kind != LightKind::Point));
        assert!(no_points || ray_kind.contains(&ShadowTarget::Point));
        if sky_only || (mixed && selection == OneSampled) {
            assert!(
                light.iter().any(|l| l.kind == LightKind::ImageInfinite) && ray_kind.contains(&ShadowTarget::Infinity)
            );
        }
        if triangles_only {
            // Both triangles sampled, with rays to their surfaces, and points the f32 bounds refuse.
            let area_lights: Vec<u32> = light.iter().filter(|l| l.kind == LightKind::Area).map(|l| l.row).collect();
            // (The BVH sampler, ranking by distance, leaves the far one to the others.)
            let both = area_lights.contains(&0) && area_lights.contains(&1);
            assert!(both || light_sampler == Bvh, "{light_sampler:?}: rows {area_lights:?}");
            assert!(ray_kind.contains(&ShadowTarget::Surface));
            let lanes = crate::light::area::TriangleLightLanes::sample(
                &table.area.items,
                &[0; LANES],
                u32::MAX >> (32 - LANES),
                &Vec3x16::splat(Vec3::new(0.0, 2.5 - 5e-5, 0.0)),
                [crate::lanes::F32x16::splat(0.3); 2],
            );
            assert!(lanes.sample.reference.all(), "a point 5e-5 under the plane is the reference's");
        }
        // (Resampling keeps the strong lights: the weak disk need not survive.)
        let every_kind = mixed && selection == OneSampled;
        assert!(!every_kind || ray_kind.contains(&ShadowTarget::Infinity));
        assert!(!every_kind || ray_kind.contains(&ShadowTarget::Surface));
        // (The power sampler's choices for the point at a light include that light.)
        let at_light = (0..m).any(|e| batch.pixel[e / k] == 0 && pdf[e] == 0.0 && light[e].kind == LightKind::Point);
        assert!(at_light || light_sampler != Power || no_points, "at the light");
    }
}

/// ReSTIR's reservoirs built in lanes (the schedule, RGB) equal those built one entry at a time,
/// bit for bit: the initial RIS reservoirs and the spatially reused ones, for points lit by the
/// lane kernels' kinds (a point light, an emissive triangle, an image light) and a spot, which
/// is sampled one lane at a time. Hard cases: a point at NaN (an escaped ray: no reservoir), one
/// exactly at the point light, and a batch length that is no multiple of the lane count.
#[test]
fn restir_reservoirs_in_lanes_equal_one_entry_at_a_time() {
    use crate::shading::{ImageLayout, LightSelection, Restir};
    let mut world = World::new();
    let mut schedule = Schedule::default();
    crate::systems::LightingPlugin::build(&mut world, &mut schedule);
    let at = |x, y, z| Transform::from_translation(Vec3::new(x, y, z));
    world.spawn((PointLight::candela(1e3), at(0.0, 2.0, 0.0)));
    let spot = SpotLight { amount: Amount::Candela(1e4), ..Default::default() };
    world.spawn((spot, at(1.0, 3.0, 0.0).looking_to(Vec3::NEG_Y, Vec3::Z)));
    let triangle = [Vec3::new(-3.0, 2.5, -3.0), Vec3::new(3.0, 2.5, -3.0), Vec3::new(0.0, 2.5, 3.0)];
    let mesh = crate::geometry::Mesh::from_triangles(&[triangle]).unwrap();
    let area = crate::light::AreaLight { two_sided: true, amount: Amount::Nits(50.0), ..Default::default() };
    world.spawn((area, mesh, at(0.0, 0.0, 0.0)));
    let (w, h) = (16, 8);
    let mut sky: Vec<Vec3> = (0..w * h).map(|i| Vec3::new(0.2, 0.3 + (i % w) as f32 * 0.05, 0.8)).collect();
    sky[3 * w + 5] = Vec3::splat(1e3);
    let image = std::sync::Arc::new(crate::scene::image::RgbImage { width: w, height: h, pixels: sky });
    world.spawn((crate::light::ImageInfiniteLight::new(image), Transform::IDENTITY));
    let restir = Restir { candidates: 4, spatial: 3, radius: 3, temporal: false, ..Restir::default() };
    world.resource_mut::<Settings>().selection = LightSelection::Restir(restir);
    {
        // A 12 x 9 image at 2 samples per pixel: 216 entries, 13.5 blocks of lanes.
        let (width, spp) = (12u32, 2u32);
        let mut batch = world.resource_mut::<ShadingBatch>();
        batch.clear();
        batch.layout = Some(ImageLayout { width, samples_per_pixel: spp, first: 0 });
        let mut rng = SplitMix64::new(5);
        for i in 0..12 * 9 * spp {
            let p = match i {
                37 => Vec3::new(f32::NAN, 0.0, 0.0),
                50 => Vec3::new(0.0, 2.0, 0.0),
                _ => Vec3::new(rng.f32() * 8.0 - 4.0, rng.f32() * 2.0, rng.f32() * 8.0 - 4.0),
            };
            batch.push(p, Vec3::Y, i / spp, i % spp);
        }
    }
    schedule.run(&mut world);
    let (batch, table, sampler, settings) = (
        world.resource::<ShadingBatch>(),
        world.resource::<LightTable>(),
        world.resource::<LightSampler>(),
        world.resource::<Settings>(),
    );
    let sampling = Sampling { batch, table, sampler, settings, all_ids: &[], k: 1, spp: 1, reservoirs: &[] };
    let mut scalar = Reservoirs::default();
    sampling.build_reservoirs(&restir, &mut scalar, batch.len(), false);
    let lanes = world.resource::<Reservoirs>();
    let bits = |r: &[reuse::Stored]| r.iter().map(reuse::Stored::bits).collect::<Vec<_>>();
    assert_eq!(bits(lanes.initial()), bits(scalar.initial()), "initial reservoirs");
    assert_eq!(bits(&lanes.next), bits(&scalar.next), "spatially reused reservoirs");
    assert!(lanes.neighbours > 0 && lanes.neighbours == scalar.neighbours);
    // Every lane kind was chosen somewhere, the escaped point got nothing.
    let kinds: Vec<LightKind> = scalar.next.iter().map(|r| r.bits().0.kind).collect();
    for kind in [LightKind::Point, LightKind::Area, LightKind::ImageInfinite] {
        assert!(kinds.contains(&kind), "{kind:?} never chosen");
    }
    assert_eq!(scalar.initial()[37].bits().0, NO_LIGHT);
}

/// The sampling pass traces each chunk's shadow rays as soon as it has sampled the chunk: its
/// answers must be those of each kept segment traced alone (`SceneBvh::occluded_from`), entry by
/// entry, and the entries must not depend on whether an app keeps the segments. Hard cases: one
/// entry per point in whole and partial blocks of lanes (packets from a lane kernel's segments),
/// three per point (a block spans points: the entry-to-point map), points spread over the scene
/// (one ray at a time), rays to points, to a light's surface and to infinity, a light that casts no
/// shadows, a slot with no point.
#[test]
fn shadow_rays_traced_in_the_sampling_pass_match_one_ray_at_a_time() {
    use crate::geometry::{Mesh, SceneBvh, SurfacePoint};
    for (samples_per_point, spread, mixed) in [(1, 0.2, false), (1, 0.2, true), (3, 0.2, true), (1, 8.0, true)] {
        let run = |keep: bool| {
            let mut world = World::new();
            let mut schedule = Schedule::default();
            crate::systems::LightingPlugin::build(&mut world, &mut schedule);
            world.resource_mut::<Settings>().samples_per_point = samples_per_point;
            world.resource_mut::<ShadowRays>().keep = keep;
            let at = |x, y, z| Transform::from_translation(Vec3::new(x, y, z));
            world.spawn((PointLight::candela(1e3), at(0.0, 3.0, 0.0)));
            world.spawn((PointLight::candela(1e3), at(2.0, 3.0, 1.0)));
            if mixed {
                world.spawn((PointLight { casts_shadows: false, ..PointLight::candela(1e3) }, at(-2.0, 3.0, 0.0)));
                world.spawn((UniformInfiniteLight::default(), Transform::default()));
                let disk = crate::geometry::Disk { radius: 0.5, inner_radius: 0.0 };
                let light = crate::light::AreaLight { two_sided: true, ..Default::default() };
                world.spawn((light, disk, at(-1.0, 3.5, -1.0)));
            }
            // Occluders between the points and the lights: a grid of small squares at y = 1.5.
            let mut squares = Vec::new();
            for i in 0..12 {
                for j in 0..12 {
                    let (x, z) = (i as f32 * 0.7 - 4.0, j as f32 * 0.7 - 4.0);
                    let [a, b, c, d] =
                        [(0.0, 0.0), (0.4, 0.0), (0.4, 0.4), (0.0, 0.4)].map(|(u, v)| Vec3::new(x + u, 1.5, z + v));
                    squares.extend([[a, b, c], [a, c, d]]);
                }
            }
            world.spawn((Mesh::from_triangles(&squares).unwrap(), Transform::IDENTITY));
            {
                let mut batch = world.resource_mut::<ShadingBatch>();
                let mut rng = SplitMix64::new(11);
                // 37 pixels of 16 samples each, around centres over the floor; one slot with no point.
                for pixel in 0..37u32 {
                    let centre = Vec3::new(rng.f32() * 6.0 - 3.0, 0.0, rng.f32() * 6.0 - 3.0);
                    for sample in 0..16 {
                        let jitter = Vec3::new(rng.f32() - 0.5, 0.0, rng.f32() - 0.5) * spread;
                        let p = if pixel == 5 && sample == 3 { Vec3::NAN } else { centre + jitter };
                        batch.push(p, Vec3::Y, pixel, sample);
                    }
                }
            }
            schedule.run(&mut world);
            world
        };
        let (kept, unkept) = (run(true), run(false));
        let case = format!("{samples_per_point} per point, spread {spread}, mixed {mixed}");
        let (lit, rays) = (kept.resource::<DirectLighting>(), kept.resource::<ShadowRays>());
        let (batch, bvh, offset) =
            (kept.resource::<ShadingBatch>(), kept.resource::<SceneBvh>(), kept.resource::<Settings>().shadow_offset);
        let k = rays.entries_per_point;
        let (mut traced, mut blocked) = (0, 0);
        for e in 0..rays.kind.len() {
            let i = e / k;
            let from = SurfacePoint { p: batch.position[i], p_error: batch.position_error[i], n: batch.normal[i] };
            let ray = match rays.kind[e] {
                ShadowTarget::None => {
                    assert!(!rays.occluded[e] && !lit.occluded[e], "{case}: entry {e} has no ray");
                    continue;
                }
                ShadowTarget::Point => offset.spawn_ray_to_point(&from, rays.target[e]),
                ShadowTarget::Infinity => offset.spawn_ray(&from, (rays.target[e] - from.p).normalize()),
                ShadowTarget::Surface => {
                    offset.spawn_ray_to(&from, &SurfacePoint::from_point(rays.target[e], rays.target_normal[e]))
                }
            };
            let alone = bvh.occluded_from(&ray, batch.geometry_of(i));
            assert_eq!(rays.occluded[e], alone, "{case}: entry {e}");
            assert_eq!(lit.occluded[e], alone, "{case}: entry {e}");
            if alone {
                assert_eq!(lit.radiance[e], SampledSpectrum::default(), "{case}: entry {e} is blocked");
            }
            (traced, blocked) = (traced + 1, blocked + alone as usize);
        }
        assert_eq!((rays.len(), rays.blocked()), (traced, blocked), "{case}");
        assert!(blocked > 0 && blocked < traced, "{case}: {blocked} of {traced} blocked");
        // Without `keep`: no columns, the same entries bit for bit.
        let (other, other_rays) = (unkept.resource::<DirectLighting>(), unkept.resource::<ShadowRays>());
        assert!(other_rays.kind.is_empty() && other_rays.occluded.is_empty());
        assert_eq!((other_rays.len(), other_rays.blocked()), (traced, blocked), "{case}");
        let bits = |d: &DirectLighting| {
            let radiance = d.radiance.iter().flat_map(|r| r.0).map(f32::to_bits).collect::<Vec<_>>();
            (radiance, d.pdf.iter().map(|p| p.to_bits()).collect::<Vec<_>>(), d.occluded.clone())
        };
        assert!(bits(lit) == bits(other), "{case}: kept and unkept segments give other entries");
    }
}

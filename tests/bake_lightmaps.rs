//! `kelvin bake lightmaps`: texels against closed forms (a quad under a point light, a spot and a
//! uniform sky; a closed white room, depth by depth), light through walls, KTX2 files read back
//! bit for bit, bad input, and Bevy's CornellBox end to end through the program.

mod common;

use std::path::Path;

use glam::Vec3;
use kelvin::bake::ktx2::{self, Format, Supercompression, Texture};
use kelvin::bake::{
    BakeError, BakeReport, BakedLight, Lightmap, LightmapOptions, TexelState, bake_lightmaps, write_lightmaps,
};
use kelvin::light::UniformInfiniteLight;
use kelvin::render::job::RenderJob;
use kelvin::render::path::PathDepth;
use kelvin::sampling::smooth_step;
use serde_json::{Value, json};

use common::files::{TempDir, test_data};
use common::gltf_doc::{Doc, cuboid, floor};

/// Luminance of linear sRGB (Rec. 709 weights, as kelvin's photometry).
fn lum(c: Vec3) -> f64 {
    kelvin::scene::image::LUMINANCE_WEIGHTS.dot(c) as f64
}

/// Bakes `doc` (written into `dir`) with `opts`; `extra` may spawn more lights into the world.
fn bake(
    dir: &TempDir,
    doc: &Doc,
    opts: &LightmapOptions,
    extra: impl FnOnce(&mut bevy_ecs::world::World),
) -> BakeReport {
    let path = dir.join("scene.gltf");
    doc.write(&path);
    let mut loaded = RenderJob { scene: Some(path), seed: 7, ..RenderJob::default() }.load().unwrap();
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    extra(&mut loaded.world);
    bake_lightmaps(&mut loaded, opts, |_| {}).unwrap()
}

/// Every baked texel's luminance against `expected(texel)` (None: not checked): their mean error
/// within 3 sigma of the mean, 98% of them within 3 sigma, and each within 5 sigma (sigma from the
/// texel's own samples, plus `floor` relative for f32 and colour rounding). A texel's spread
/// underestimates its error now and then where its samples are skewed (roulette's long paths
/// multiply the variance tenfold in the furnace; their spread over many texels still matches the
/// spread over seeds), hence 98% and 5 sigma for the worst of hundreds.
fn check_texels(map: &Lightmap, expected: impl Fn(usize) -> Option<f64>, floor: f64, what: &str) {
    let (mut n, mut within3, mut err_sum, mut var_sum, mut e_sum) = (0usize, 0usize, 0.0f64, 0.0f64, 0.0f64);
    let mut worst: Option<(f64, String)> = None;
    for (i, (&t, &state)) in map.texels.iter().zip(&map.state).enumerate() {
        let Some(e) = expected(i).filter(|_| state == TexelState::Baked) else { continue };
        let (m, s) = (lum(t), lum(map.std_error[i]));
        let tol = floor * e.abs() + 1e-9;
        let z = ((m - e).abs() - tol).max(0.0) / s.max(1e-30);
        if worst.as_ref().is_none_or(|w| z > w.0) {
            worst = Some((z, format!("texel {i}: {m} vs {e} (sigma {s})")));
        }
        within3 += (z <= 3.0) as usize;
        (n, err_sum, var_sum, e_sum) = (n + 1, err_sum + (m - e), var_sum + s * s, e_sum + e);
    }
    assert!(n > 0, "{what}: no texel checked");
    let (mean_err, sigma) = (err_sum / n as f64, var_sum.sqrt() / n as f64);
    let (z, worst) = worst.unwrap_or_default();
    eprintln!(
        "{what}: {n} texels, mean error {mean_err:.3e} (sigma of the mean {sigma:.3e}), {within3} within 3 sigma, worst {worst} at {z:.2} sigma"
    );
    // f32 sums of many samples round at a few parts in 10^7.
    let rounding = 1e-5 * e_sum / n as f64;
    assert!(mean_err.abs() <= 3.0 * sigma + rounding, "{what}: mean error {mean_err} vs sigma {sigma}");
    assert!(within3 as f64 >= 0.98 * n as f64 - 1.0, "{what}: {within3} of {n} texels within 3 sigma");
    assert!(z <= 5.0, "{what}: {worst} is {z:.2} sigma off");
}

/// The mean over texel `i` of a `size` x `size` lightmap on the quad [-1, 1]^2 (y = 0) of `f(x, z)`,
/// by the midpoint rule on 12 x 12 points.
fn texel_mean(i: usize, size: usize, f: impl Fn(f64, f64) -> f64) -> f64 {
    let (tx, tz) = ((i % size) as f64, (i / size) as f64);
    let k = 12;
    let mut sum = 0.0;
    for a in 0..k {
        for b in 0..k {
            let x = -1.0 + 2.0 * (tx + (a as f64 + 0.5) / k as f64) / size as f64;
            let z = -1.0 + 2.0 * (tz + (b as f64 + 0.5) / k as f64) / size as f64;
            sum += f(x, z);
        }
    }
    sum / (k * k) as f64
}

const SIZE: usize = 16;

fn quad_doc() -> Doc {
    let mut doc = Doc::default();
    let m = doc.material(0.8, 0.0);
    doc.mesh("quad", &[floor([-1.0, 1.0], [-1.0, 1.0], 0.0, m)]);
    doc
}

fn quad_options() -> LightmapOptions {
    LightmapOptions { size: SIZE as u32, spp: 64, ..LightmapOptions::default() }
}

#[test]
fn a_point_light_gives_e_over_pi_at_every_texel() {
    let dir = TempDir::new("bake", "point");
    let mut doc = quad_doc();
    let (light, intensity) = (Vec3::new(0.3, 1.0, -0.2), 10.0);
    doc.light(json!({ "type": "point", "intensity": intensity }), light, [0.0, 0.0, 0.0, 1.0]);
    let report = bake(&dir, &doc, &quad_options(), |_| {});
    let map = &report.lightmaps[0];
    assert_eq!((report.lightmaps.len(), map.name.as_str(), map.size), (1, "quad", SIZE as u32));
    // E = I cos(theta) / d^2 = I h / d^3; the texel holds E / pi.
    let e = |x: f64, z: f64| {
        let d = Vec3::new(light.x - x as f32, light.y, light.z - z as f32).as_dvec3();
        intensity * d.y / d.length().powi(3) / std::f64::consts::PI
    };
    assert!(map.state.iter().all(|s| *s == TexelState::Baked));
    check_texels(map, |i| Some(texel_mean(i, SIZE, e)), 1e-3, "point light");
}

#[test]
fn a_spot_light_gives_e_over_pi_inside_and_nothing_outside_its_cone() {
    let dir = TempDir::new("bake", "spot");
    let mut doc = quad_doc();
    let (height, intensity, inner, outer) = (1.2f64, 20.0, 0.3f64, 0.6f64);
    let spot =
        json!({ "type": "spot", "intensity": intensity, "spot": { "innerConeAngle": inner, "outerConeAngle": outer } });
    // Aimed down: -Z turned onto -Y (a quarter turn about X).
    let half = std::f32::consts::FRAC_1_SQRT_2;
    doc.light(spot, Vec3::new(0.0, height as f32, 0.0), [-half, 0.0, 0.0, half]);
    let report = bake(&dir, &doc, &quad_options(), |_| {});
    let map = &report.lightmaps[0];
    let e = |x: f64, z: f64| {
        let d = (x * x + z * z + height * height).sqrt();
        let falloff = smooth_step((height / d) as f32, outer.cos() as f32, inner.cos() as f32) as f64;
        intensity * falloff * height / d.powi(3) / std::f64::consts::PI
    };
    // Texels across the cone's edge hold the light in a sliver that few samples find: their
    // spread says little about their error, so they are left out.
    let edge = height * outer.tan();
    let across_edge = |i: usize| {
        let side = 2.0 / SIZE as f64;
        let (x0, z0) = (-1.0 + side * (i % SIZE) as f64, -1.0 + side * (i / SIZE) as f64);
        let (x1, z1) = (x0 + side, z0 + side);
        let near = 0f64.clamp(x0, x1).hypot(0f64.clamp(z0, z1));
        let far = x0.abs().max(x1.abs()).hypot(z0.abs().max(z1.abs()));
        near < edge && far > edge
    };
    let crossing = (0..SIZE * SIZE).filter(|&i| across_edge(i)).count();
    assert!(crossing < SIZE * SIZE / 4, "{crossing}");
    check_texels(map, |i| (!across_edge(i)).then(|| texel_mean(i, SIZE, e)), 1e-3, "spot light");
    // The corners lie outside the outer cone (tan 0.6 * 1.2 = 0.82 < 1): nothing at all.
    for corner in [0, SIZE - 1, SIZE * (SIZE - 1), SIZE * SIZE - 1] {
        assert_eq!(map.texels[corner], Vec3::ZERO, "corner texel {corner}");
    }
}

#[test]
fn a_uniform_sky_gives_its_radiance_at_every_texel() {
    let dir = TempDir::new("bake", "sky");
    let nits = 250.0;
    let report = bake(&dir, &quad_doc(), &quad_options(), |world| {
        world.spawn((UniformInfiniteLight::nits(nits), kelvin::geometry::Transform::IDENTITY));
    });
    // E = pi L over the open hemisphere: E / pi = L.
    check_texels(&report.lightmaps[0], |_| Some(nits as f64), 1e-3, "uniform sky");
}

/// A closed cube, faces inward, Lambertian of albedo `RHO`, every face emitting `LE` nit.
fn furnace_doc() -> Doc {
    let mut doc = Doc::default();
    let m = doc.material(RHO as f32, LE as f32);
    doc.mesh("room", &[cuboid(Vec3::splat(-1.0), Vec3::ONE, true, true, m)]);
    doc
}
const RHO: f64 = 0.5;
const LE: f64 = 3.0;

/// Radiance is Le / (1 - rho) everywhere in the room; a path that may reach `depth` surfaces after
/// the texel sees Le (1 + rho + ... + rho^(depth - 1)) of it: the geometric series, bounce by bounce.
#[test]
fn a_closed_white_room_follows_the_geometric_series_of_its_albedo() {
    let dir = TempDir::new("bake", "furnace");
    let doc = furnace_doc();
    let series = |from: i32, to: i32| (from..to).map(|k| LE * RHO.powi(k)).sum::<f64>();
    let cases = [
        (1, BakedLight::All, series(0, 1)),
        (2, BakedLight::All, series(0, 2)),
        (3, BakedLight::All, series(0, 3)),
        (3, BakedLight::Indirect, series(1, 3)),
        // Roulette from the fourth surface on keeps the estimate unbiased.
        (PathDepth::DEFAULT.max_depth, BakedLight::All, series(0, PathDepth::DEFAULT.max_depth as i32)),
        (PathDepth::DEFAULT.max_depth, BakedLight::Indirect, series(1, PathDepth::DEFAULT.max_depth as i32)),
    ];
    for (depth, light, expected) in cases {
        let opts = LightmapOptions {
            size: 24,
            // Roulette makes a texel's samples skewed (a few long paths): enough of them that
            // their spread is a fair estimate of the error.
            spp: 256,
            depth: PathDepth { max_depth: depth, ..PathDepth::DEFAULT },
            light,
            ..LightmapOptions::default()
        };
        let report = bake(&dir, &doc, &opts, |_| {});
        let map = &report.lightmaps[0];
        assert_eq!(map.leaked_samples, 0, "inside a closed room every ray meets a front face");
        check_texels(map, |_| Some(expected), 1e-3, &format!("furnace depth {depth} {light:?}"));
    }
}

/// A floor with a thick wall standing across it and a point light on one side: after dilation,
/// no texel beyond the wall holds 1e-3 of the lit side's light. The texels under the wall have
/// only samples inside it (dropped as leaks) and are filled from their own side.
#[test]
fn no_light_passes_under_a_wall() {
    let dir = TempDir::new("bake", "wall");
    let mut doc = Doc::default();
    let m = doc.material(0.8, 0.0);
    // 16 texels across 4 m: 0.25 m each; the wall covers x in [-0.3, 0.3], part of 4 columns.
    doc.mesh("floor", &[floor([-2.0, 2.0], [-1.0, 1.0], 0.0, m)]);
    doc.mesh("wall", &[cuboid(Vec3::new(-0.3, 0.0, -1.5), Vec3::new(0.3, 2.0, 1.5), false, false, m)]);
    doc.light(json!({ "type": "point", "intensity": 50.0 }), Vec3::new(-1.0, 1.0, 0.0), [0.0, 0.0, 0.0, 1.0]);
    let report = bake(&dir, &doc, &LightmapOptions { size: 16, spp: 32, ..LightmapOptions::default() }, |_| {});
    assert_eq!(report.lightmaps.len(), 1);
    assert!(
        report.skipped.iter().any(|s| s.contains("mesh wall") && s.contains("no TEXCOORD_1")),
        "{:?}",
        report.skipped
    );
    let map = &report.lightmaps[0];
    assert!(map.leaked_samples > 0);
    let column_x = |i: usize| -2.0 + 0.25 * ((i % 16) as f64 + 0.5);
    let lit: Vec<f64> = (0..256).filter(|&i| column_x(i) < -0.3).map(|i| lum(map.texels[i])).collect();
    let lit_mean = lit.iter().sum::<f64>() / lit.len() as f64;
    assert!(lit_mean > 1.0, "the lit side is lit: {lit_mean}");
    for i in (0..256).filter(|&i| column_x(i) > 0.0) {
        let v = lum(map.texels[i]);
        assert!(v < 1e-3 * lit_mean, "texel {i} (x = {}) beyond the wall holds {v} (lit side {lit_mean})", column_x(i));
    }
    // Columns 7 and 8 lie wholly under the wall: no valid sample, filled by dilation.
    for i in (0..256).filter(|i| matches!(i % 16, 7 | 8)) {
        assert_eq!(map.state[i], TexelState::Filled, "texel {i}");
    }
    // Direct light alone (depth 1) from a point light: no BSDF ray can find light, but the leak
    // test still traces the first ray, and drops the same samples.
    let depth = PathDepth { max_depth: 1, ..PathDepth::DEFAULT };
    let direct = bake(&dir, &doc, &LightmapOptions { size: 16, spp: 32, depth, ..LightmapOptions::default() }, |_| {});
    assert_eq!(direct.lightmaps[0].leaked_samples, map.leaked_samples);
    for i in (0..256).filter(|i| matches!(i % 16, 7 | 8)) {
        assert_eq!(direct.lightmaps[0].state[i], TexelState::Filled, "texel {i} at depth 1");
    }
}

/// A box standing on a floor under a uniform sky: a floor point outside the box sees at least half
/// of the sky's cosine-weighted hemisphere (a vertical plane through it separates it from the
/// box), so every texel holds at least L / 2. Texels the box's edge crosses keep only samples
/// outside it: taking the ones inside (which see nothing) would darken them to about a third.
/// A double-sided material (Blender's default) changes none of it: the box still has an inside.
#[test]
fn a_box_on_the_floor_does_not_darken_the_floor_beyond_its_contact() {
    for double_sided in [false, true] {
        box_on_the_floor(double_sided);
    }
}

fn box_on_the_floor(double_sided: bool) {
    let dir = TempDir::new("bake", "box");
    let mut doc = Doc::default();
    let m = doc.material(0.5, 0.0);
    if double_sided {
        doc.double_sided(m);
    }
    doc.mesh("floor", &[floor([-2.0, 2.0], [-2.0, 2.0], 0.0, m)]);
    // Edges at x, z = +-0.6: inside texel columns 5 and 10 (0.25 m each), not on their borders.
    doc.mesh("box", &[cuboid(Vec3::new(-0.6, 0.0, -0.6), Vec3::new(0.6, 1.0, 0.6), false, false, m)]);
    let nits = 100.0;
    let bake_to = |depth| {
        let opts = LightmapOptions { size: 16, spp: 64, depth, ..LightmapOptions::default() };
        bake(&dir, &doc, &opts, |world| {
            world.spawn((UniformInfiniteLight::nits(nits), kelvin::geometry::Transform::IDENTITY));
        })
    };
    let report = bake_to(PathDepth::DEFAULT);
    let map = &report.lightmaps[0];
    // Direct light alone (depth 1), where the first ray is also the last: the leak test still
    // reads its hits, and drops the same samples.
    let direct = bake_to(PathDepth { max_depth: 1, ..PathDepth::DEFAULT });
    assert!(map.leaked_samples > 0);
    assert_eq!(direct.lightmaps[0].leaked_samples, map.leaked_samples);
    let half = 0.5 * nits as f64;
    let (mut crossed, mut filled) = (0, 0);
    for (i, state) in map.state.iter().enumerate() {
        let (v, s) = (lum(map.texels[i]), lum(map.std_error[i]));
        let (cx, cz) = (i % 16, i / 16);
        let edge = |c: usize| c == 5 || c == 10;
        let inside = |c: usize| (5..=10).contains(&c);
        if (edge(cx) && inside(cz)) || (edge(cz) && inside(cx)) {
            assert_eq!(*state, TexelState::Baked, "texel {i}: partly outside the box (double-sided {double_sided})");
            crossed += 1;
        }
        match state {
            TexelState::Baked => {
                assert!(v >= half - 4.0 * s, "texel {i}: {v} < L / 2 = {half} (sigma {s}; double-sided {double_sided})")
            }
            TexelState::Filled => {
                filled += 1;
                assert!(v >= 0.9 * half, "filled texel {i}: {v}");
            }
            TexelState::Empty => panic!("texel {i} is empty"),
        }
    }
    // 4 x 4 texels lie wholly under the box; the margin of 4 rings reaches all of them.
    assert_eq!((crossed, filled), (20, 16), "double-sided {double_sided}");
}

/// Bevy's CornellBox as Blender exported it, every material double-sided: a floor texel wholly
/// under the large box keeps no sample (every ray from there meets the inside of the box), so it
/// is filled from the floor around it or left empty, never baked from the box's dark inside.
/// Issue 61: ~50 such texels were baked, ~0.3 nit where Cycles has ~0.
#[test]
fn cornell_box_floor_under_its_double_sided_box_keeps_no_sample() {
    let job = RenderJob { scene: Some(test_data("gltf/bevy/CornellBox.glb")), seed: 7, ..RenderJob::default() };
    let mut loaded = job.load().unwrap();
    // The floor's triangles (uv1 and world corners) and the large box's upright faces (a point, the normal).
    let (mut floor_tris, mut walls) = (Vec::new(), Vec::new());
    for p in &loaded.primitives {
        let material = loaded.world.get::<kelvin::render::material::Material>(p.entity).unwrap();
        assert!(material.double_sided, "{:?}: the file's materials are all double-sided", p.mesh_name);
        let mesh = loaded.world.get::<kelvin::geometry::Mesh>(p.entity).unwrap();
        for t in 0..mesh.triangle_count() {
            let [a, b, c] = mesh.triangle(t);
            let n = (b - a).cross(c - a).normalize();
            match (p.mesh_name.as_deref(), &p.uvs1) {
                (Some("cornell_box"), Some(uv)) if n.y.abs() > 0.99 && a.y.abs() < 1.0 => {
                    floor_tris.push((mesh.triangle_indices(t).map(|i| uv[i as usize]), [a, b, c]));
                }
                (Some("large_box"), _) if n.y.abs() < 0.01 => walls.push((a, n)),
                _ => {}
            }
        }
    }
    assert_eq!((floor_tris.len(), walls.len()), (2, 8));
    // The floor point at `uv`, by the affine map of the floor triangle whose uv1 holds `centre`.
    let floor_at = |centre: glam::Vec2, uv: glam::Vec2| {
        floor_tris.iter().find_map(|(t, p)| {
            let (e1, e2, d) = (t[1] - t[0], t[2] - t[0], centre - t[0]);
            let det = e1.perp_dot(e2);
            let (b1, b2) = (d.perp_dot(e2) / det, e1.perp_dot(d) / det);
            (b1 >= 0.0 && b2 >= 0.0 && b1 + b2 <= 1.0).then(|| {
                let q = uv - t[0];
                let (c1, c2) = (q.perp_dot(e2) / det, e1.perp_dot(q) / det);
                p[0] + c1 * (p[1] - p[0]) + c2 * (p[2] - p[0])
            })
        })
    };
    let under_box = |p: Vec3| walls.iter().all(|(a, n)| (p - *a).dot(*n) < 0.0);
    let size = 64;
    let opts = LightmapOptions { size, spp: 16, ..LightmapOptions::default() };
    let report = bake_lightmaps(&mut loaded, &opts, |_| {}).unwrap();
    let map = report.lightmaps.iter().find(|m| m.mesh_name.as_deref() == Some("cornell_box")).unwrap();
    let mut under = 0;
    for (i, state) in map.state.iter().enumerate() {
        let texel = glam::Vec2::new((i as u32 % size) as f32, (i as u32 / size) as f32);
        let centre = (texel + 0.5) / size as f32;
        let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
            .map(|(x, y)| (texel + glam::Vec2::new(x, y)) / size as f32);
        let Some(points) = corners.iter().map(|&uv| floor_at(centre, uv)).collect::<Option<Vec<Vec3>>>() else {
            continue;
        };
        if points.iter().all(|&p| under_box(p)) {
            under += 1;
            assert_ne!(
                *state,
                TexelState::Baked,
                "texel {i} at {} lies wholly under the large box: {}",
                points[0],
                map.texels[i]
            );
        }
    }
    eprintln!("{under} texels wholly under the large box; {} samples dropped", map.leaked_samples);
    assert!(under >= 20, "{under} texels under the box");
}

#[test]
fn ktx2_files_read_back_bit_for_bit() {
    let mut rng = kelvin::rng::SplitMix64::new(11);
    for format in [Format::B10G11R11, Format::E5B9G9R9] {
        for (width, height, depth) in [(7, 5, 0), (4, 6, 3), (1, 1, 0)] {
            for supercompression in [Supercompression::None, Supercompression::Zstd(3)] {
                let n = (width * height * depth.max(1)) as usize;
                let texels: Vec<Vec3> = (0..n)
                    .map(|k| match k {
                        0 => Vec3::new(0.0, 1.0, 65000.0),
                        1 => Vec3::new(-1.0, f32::NAN, 1e-7),
                        _ => Vec3::new(rng.log_range(1e-4, 1e4), rng.log_range(1e-4, 1e4), rng.f32()),
                    })
                    .collect();
                let texture = Texture { format, width, height, depth, texels: &texels };
                let bytes = ktx2::encode(&texture, supercompression).unwrap();
                let what = format!("{format:?} {width}x{height}x{depth} {supercompression:?}");
                let reader = ::ktx2::Reader::new(&bytes[..]).unwrap_or_else(|e| panic!("{what}: {e:?}"));
                let header = reader.header();
                let expected_format = match format {
                    Format::B10G11R11 => ::ktx2::Format::B10G11R11_UFLOAT_PACK32,
                    Format::E5B9G9R9 => ::ktx2::Format::E5B9G9R9_UFLOAT_PACK32,
                };
                assert_eq!(header.format, Some(expected_format), "{what}");
                assert_eq!(
                    (header.type_size, header.pixel_width, header.pixel_height, header.pixel_depth),
                    (4, width, height, depth)
                );
                assert_eq!((header.layer_count, header.face_count, header.level_count), (0, 1, 1), "{what}");
                let zstd = supercompression != Supercompression::None;
                let scheme = zstd.then_some(::ktx2::SupercompressionScheme::Zstandard);
                assert_eq!(header.supercompression_scheme, scheme, "{what}");
                assert_eq!(
                    reader.writer().map(|w| w.trim_end_matches('\0')),
                    Some(concat!("kelvin ", env!("CARGO_PKG_VERSION")))
                );
                // The descriptor is the one the ktx2 crate derives from the format on its own.
                let (expected_dfd, _) = ::ktx2::dfd::Basic::from_format(expected_format).unwrap();
                assert_eq!(reader.basic_dfd(), Some(&expected_dfd), "{what}");
                let levels: Vec<_> = reader.levels().collect();
                assert_eq!(levels.len(), 1);
                let raw = if zstd { ::zstd::decode_all(levels[0].data).unwrap() } else { levels[0].data.to_vec() };
                assert_eq!((raw.len() as u64, levels[0].uncompressed_byte_length), (4 * n as u64, 4 * n as u64));
                for (k, t) in texels.iter().enumerate() {
                    let word = u32::from_le_bytes(raw[4 * k..4 * k + 4].try_into().unwrap());
                    assert_eq!(word, format.pack(*t), "{what}: texel {k}");
                    let back = format.unpack(word);
                    // Within the format's precision: half a step of a 5-bit mantissa (B of
                    // B10G11R11), or of the shared exponent set by the largest channel.
                    let largest = match format {
                        Format::B10G11R11 => Vec3::new(65024.0, 65024.0, 64512.0),
                        Format::E5B9G9R9 => Vec3::splat(65408.0),
                    };
                    let expected = t.max(Vec3::ZERO).min(largest);
                    let expected = Vec3::select(expected.is_nan_mask(), Vec3::ZERO, expected);
                    let tolerance = match format {
                        Format::B10G11R11 => expected * 2f32.powi(-6) + Vec3::splat(2f32.powi(-20)),
                        Format::E5B9G9R9 => Vec3::splat(expected.max_element() * 2f32.powi(-8) + 2f32.powi(-25)),
                    };
                    assert!((back - expected).abs().cmple(tolerance).all(), "{what}: {t} -> {back}");
                }
            }
        }
    }
    let bad = Texture { format: Format::E5B9G9R9, width: 2, height: 2, depth: 0, texels: &[Vec3::ONE; 3] };
    assert!(
        ktx2::encode(&bad, Supercompression::None).unwrap_err().to_string().contains("3 texels given for a 2 x 2 x 0")
    );
}

/// The program bakes Bevy's CornellBox: one EXR and one KTX2 per mesh (their texels the same
/// values, bit for bit after packing) and the index, which names the mesh of each.
#[test]
fn cornell_box_bakes_end_to_end_through_the_program() {
    let dir = TempDir::new("bake", "cornell");
    let out = dir.join("maps");
    let scene = test_data("gltf/bevy/CornellBox.glb");
    let args =
        ["bake", "lightmaps", scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "--size", "32", "--spp", "8"];
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_kelvin")).args(args).output().unwrap();
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let index: Value = serde_json::from_slice(&std::fs::read(out.join("lightmaps.json")).unwrap()).unwrap();
    let maps = index["lightmaps"].as_object().unwrap();
    let mut meshes: Vec<&str> = maps.values().map(|m| m["mesh"].as_str().unwrap()).collect();
    meshes.sort();
    assert_eq!(meshes, ["Light", "cornell_box", "large_box", "small_box"]);
    for (name, map) in maps {
        assert_eq!(map["uv_rect"], json!([0.0, 0.0, 1.0, 1.0]));
        assert!(
            map["lightmap_exposure"].as_f64().unwrap() > 0.0 && map["mean_luminance"].as_f64().unwrap() > 0.0,
            "{name}"
        );
        let (w, h, exr) = kelvin::render::film_io::read_exr(&out.join(map["exr"].as_str().unwrap())).unwrap();
        assert_eq!((w, h), (32, 32));
        let bytes = std::fs::read(out.join(map["image"].as_str().unwrap())).unwrap();
        let reader = ::ktx2::Reader::new(&bytes[..]).unwrap();
        assert_eq!(reader.header().supercompression_scheme, Some(::ktx2::SupercompressionScheme::Zstandard));
        let raw = ::zstd::decode_all(reader.levels().next().unwrap().data).unwrap();
        for (k, t) in exr.iter().enumerate() {
            assert_eq!(u32::from_le_bytes(raw[4 * k..4 * k + 4].try_into().unwrap()), Format::B10G11R11.pack(*t));
        }
    }
    assert_eq!(index["light"], "all");
    // The meter reading of the mean luminance: a few nit give an EV100 of a few stops.
    let means: Vec<f64> = maps.values().map(|m| m["mean_luminance"].as_f64().unwrap()).collect();
    let ev100 = index["camera_ev100"].as_f64().unwrap();
    let lo = (means.iter().copied().fold(f64::MAX, f64::min) * 8.0).log2();
    let hi = (means.iter().copied().fold(0.0, f64::max) * 8.0).log2();
    assert!((lo..=hi).contains(&ev100), "{ev100} outside [{lo}, {hi}]");
}

#[test]
fn bad_input_gives_clear_errors() {
    let dir = TempDir::new("bake", "bad");
    // A mesh without TEXCOORD_1: nothing to bake.
    let mut doc = Doc::default();
    let m = doc.material(0.5, 0.0);
    let mut quad = floor([-1.0, 1.0], [-1.0, 1.0], 0.0, m);
    quad.uv1 = None;
    doc.mesh("plain", &[quad]);
    let path = dir.join("plain.gltf");
    doc.write(&path);
    let mut loaded = RenderJob { scene: Some(path.clone()), ..RenderJob::default() }.load().unwrap();
    let err = bake_lightmaps(&mut loaded, &LightmapOptions::default(), |_| {}).unwrap_err();
    assert!(matches!(err, BakeError::NothingToBake(_)), "{err}");
    assert!(err.to_string().contains("none of the scene's 1 placed meshes has TEXCOORD_1"), "{err}");
    // Options out of range.
    for (opts, says) in [
        (LightmapOptions { size: 0, ..LightmapOptions::default() }, "size = 0 is outside 1..=4096"),
        (LightmapOptions { spp: 0, ..LightmapOptions::default() }, "spp = 0 is outside 1..=1048576"),
        (LightmapOptions { leak_distance: Some(f32::NAN), ..LightmapOptions::default() }, "leak_distance = NaN"),
    ] {
        let err = bake_lightmaps(&mut loaded, &opts, |_| {}).unwrap_err();
        assert!(err.to_string().contains(says), "{err}");
    }
    // Through the program: no uv1, a missing file, size 0.
    let kelvin = |args: &[&str]| {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_kelvin")).args(args).output().unwrap();
        assert!(!out.status.success(), "{args:?} succeeded");
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let never = dir.join("never");
    let never = never.to_str().unwrap();
    let err = kelvin(&["bake", "lightmaps", path.to_str().unwrap(), "-o", never]);
    assert!(err.contains("plain.gltf: nothing to bake: none of the scene's 1 placed meshes has TEXCOORD_1"), "{err}");
    let err = kelvin(&["bake", "lightmaps", "no-such-scene.glb", "-o", never]);
    assert!(err.contains("no-such-scene.glb: file not found"), "{err}");
    let err = kelvin(&["bake", "lightmaps", path.to_str().unwrap(), "-o", never, "--size", "0"]);
    assert!(err.contains("invalid value '0' for '--size <SIZE>': 0 is not in 1..=4096"), "{err}");
    assert!(!Path::new(never).exists(), "nothing written on failure");
}

/// The same bake on one thread and on three gives the same texels, bit for bit.
#[test]
fn lightmaps_are_the_same_for_any_thread_count() {
    let dir = TempDir::new("bake", "threads");
    let doc = furnace_doc();
    let opts = LightmapOptions { size: 12, spp: 8, ..LightmapOptions::default() };
    let on = |threads| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| bake(&dir, &doc, &opts, |_| {}).lightmaps.remove(0).texels)
    };
    assert_eq!(on(1), on(3));
}

/// The lightmaps written by `write_lightmaps` hold the report's texels.
#[test]
fn written_files_hold_the_baked_texels() {
    let dir = TempDir::new("bake", "write");
    let opts = LightmapOptions { size: 8, spp: 4, ..LightmapOptions::default() };
    let report = bake(&dir, &furnace_doc(), &opts, |_| {});
    let written = write_lightmaps(&dir.join("out"), &report, &opts).unwrap();
    let names: Vec<String> = written.iter().map(|p| p.file_name().unwrap().to_string_lossy().into_owned()).collect();
    assert_eq!(names, ["room.exr", "room.ktx2", "lightmaps.json"]);
    let (_, _, exr) = kelvin::render::film_io::read_exr(&written[0]).unwrap();
    assert_eq!(exr, report.lightmaps[0].texels);
}

/// Under a time budget the bake takes whole passes of `spp`, each continuing every texel's
/// streams: P passes of 4 paths hold the samples of one pass of 4 P (the same texels but for the
/// order of the sums). A budget of 0 is one pass.
#[test]
fn a_time_budget_takes_whole_passes_of_new_samples() {
    let dir = TempDir::new("bake", "time");
    let mut doc = quad_doc();
    doc.light(json!({ "type": "point", "intensity": 10.0 }), Vec3::new(0.3, 1.0, -0.2), [0.0, 0.0, 0.0, 1.0]);
    let opts = |spp, time| LightmapOptions { size: 8, spp, time, ..LightmapOptions::default() };
    let once = bake(&dir, &doc, &opts(4, Some(0.0)), |_| {});
    assert_eq!(once.stats.spp, 4);
    let timed = bake(&dir, &doc, &opts(4, Some(0.2)), |_| {});
    let spp = timed.stats.spp;
    assert!(spp > 4 && spp % 4 == 0 && timed.stats.seconds >= 0.2, "{spp} spp in {} s", timed.stats.seconds);
    let whole = bake(&dir, &doc, &opts(u32::try_from(spp).unwrap(), None), |_| {});
    for (a, b) in timed.lightmaps[0].texels.iter().zip(&whole.lightmaps[0].texels) {
        assert!((*a - *b).abs().max_element() <= 1e-6 * b.max_element(), "{a} vs {b}");
    }
    assert_ne!(timed.lightmaps[0].texels, once.lightmaps[0].texels);
    let err = bake_lightmaps(
        &mut RenderJob { scene: Some(dir.join("scene.gltf")), ..RenderJob::default() }.load().unwrap(),
        &opts(4, Some(-1.0)),
        |_| {},
    )
    .unwrap_err();
    assert!(err.to_string().contains("time = -1 is outside [0, 10000000)"), "{err}");
}

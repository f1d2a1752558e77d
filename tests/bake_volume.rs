//! `kelvin bake volume`: ambient cubes against closed forms (a uniform sky on every side; light from
//! +X only on the +X side alone, read face by face from the KTX2 file in Bevy's layout), voxels
//! inside geometry (double-sided or not; Bevy's CornellBox) filled from their neighbours, bad
//! input, and the layout against the volume Bevy ships for its example scene.

mod common;

use glam::{UVec3, Vec3};
use kelvin::bake::ktx2::Format;
use kelvin::bake::volume::SIDES;
use kelvin::bake::{BakeError, IrradianceVolume, TexelState, VolumeOptions, bake_volume, write_volume};
use kelvin::geometry::Mesh;
use kelvin::light::UniformInfiniteLight;
use kelvin::render::job::RenderJob;
use kelvin::render::material::Material;
use serde_json::json;

use common::files::{TempDir, test_data};
use common::gltf_doc::{Doc, cuboid};

fn lum(c: Vec3) -> f64 {
    kelvin::scene::image::LUMINANCE_WEIGHTS.dot(c) as f64
}

/// Bakes `doc` (written into `dir`) with `opts`; `extra` may spawn more lights into the world.
fn bake(
    dir: &TempDir,
    doc: &Doc,
    opts: &VolumeOptions,
    extra: impl FnOnce(&mut bevy_ecs::world::World),
) -> Result<IrradianceVolume, BakeError> {
    let path = dir.join("scene.gltf");
    doc.write(&path);
    let mut loaded = RenderJob { scene: Some(path), seed: 3, ..RenderJob::default() }.load().unwrap();
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    extra(&mut loaded.world);
    bake_volume(&mut loaded, opts, |_| {})
}

fn sky(world: &mut bevy_ecs::world::World) {
    world.spawn((UniformInfiniteLight::nits(NITS), kelvin::geometry::Transform::IDENTITY));
}
const NITS: f32 = 40.0;

fn options(resolution: UVec3, bounds: (Vec3, Vec3)) -> VolumeOptions {
    VolumeOptions { resolution, spp: 32, bounds: Some(bounds), ..VolumeOptions::default() }
}

/// In open space under a sun and sky (no ground geometry) the light's own ground is a Lambertian
/// bounce of albedo a of the sun and sky: the -Y side (E / pi of the lower hemisphere) is a times
/// the +Y side (E / pi of the upper one).
#[test]
fn a_sun_and_sky_light_the_minus_y_side_with_their_ground() {
    use kelvin::light::infinite::sunsky::{SunPosition, SunSkyLight, direction_from_angles};
    let dir = TempDir::new("volume", "sunsky");
    let opts = VolumeOptions { spp: 1024, ..options(UVec3::ONE, (Vec3::splat(-1.0), Vec3::splat(1.0))) };
    let albedo = 0.3;
    let light = SunSkyLight {
        sun: SunPosition::Direction(direction_from_angles(35.0, 200.0)),
        ground_albedo: albedo,
        ..Default::default()
    };
    let volume = bake(&dir, &Doc::default(), &opts, |w| {
        w.spawn(light);
    })
    .unwrap();
    let side = |v: Vec3| SIDES.iter().position(|s| *s == v).unwrap();
    let (up, down) = (side(Vec3::Y), side(Vec3::NEG_Y));
    let (u, d) = (lum(volume.sides[0][up]), lum(volume.sides[0][down]));
    let (su, sd) = (lum(volume.std_error[0][up]), lum(volume.std_error[0][down]));
    eprintln!("+Y {u:.1} +- {su:.1} nit, -Y {d:.1} +- {sd:.1} nit (albedo {albedo})");
    let sigma = (sd * sd + (albedo as f64 * su).powi(2)).sqrt();
    assert!((d - albedo as f64 * u).abs() <= 3.0 * sigma + 0.01 * d, "-Y {d} vs {albedo} x +Y {u} (sigma {sigma})");
}

/// In open space under a uniform sky of radiance L, each side of each voxel sees a hemisphere of
/// it: E / pi = L.
#[test]
fn a_uniform_sky_gives_its_radiance_on_every_side() {
    let dir = TempDir::new("volume", "sky");
    let opts = options(UVec3::new(3, 2, 4), (Vec3::splat(-1.0), Vec3::new(2.0, 1.0, 3.0)));
    let volume = bake(&dir, &Doc::default(), &opts, sky).unwrap();
    assert_eq!((volume.sides.len(), volume.inside), (24, 0));
    for (v, sides) in volume.sides.iter().enumerate() {
        for (s, side) in sides.iter().enumerate() {
            let (value, sigma) = (lum(*side), lum(volume.std_error[v][s]));
            assert_eq!(volume.state[v][s], TexelState::Baked);
            assert!((value - NITS as f64).abs() <= 3.0 * sigma + 1e-4 * NITS as f64, "voxel {v} side {s}: {value}");
        }
    }
    assert_eq!(volume.voxel_center(UVec3::ZERO), Vec3::new(-0.5, -0.5, -0.5));
    assert_eq!((volume.center(), volume.scale()), (Vec3::new(0.5, 0.0, 1.0), Vec3::new(3.0, 2.0, 4.0)));
}

/// Light from +X only (a distant light of E lux travelling toward -X): the +X side of every voxel
/// holds E / pi, the other five nothing. Read back from the file, each side's block of Bevy's
/// layout must hold that side: positive sides in rows [0, Ry), negative ones in [Ry, 2 Ry), the
/// X, Y and Z sides in slices [0, Rz), [Rz, 2 Rz), [2 Rz, 3 Rz).
#[test]
fn light_from_plus_x_lands_on_the_plus_x_sides_of_the_file() {
    let dir = TempDir::new("volume", "plus-x");
    let mut doc = Doc::default();
    let lux = 300.0;
    // A quarter turn about +Y takes the light's -Z onto -X.
    let half = std::f32::consts::FRAC_1_SQRT_2;
    doc.light(json!({ "type": "directional", "intensity": lux }), Vec3::ZERO, [0.0, half, 0.0, half]);
    let r = UVec3::new(2, 3, 4);
    let volume = bake(&dir, &doc, &options(r, (Vec3::ZERO, Vec3::ONE)), |_| {}).unwrap();
    let expected = |s: usize| if SIDES[s] == Vec3::X { lux / std::f64::consts::PI } else { 0.0 };
    for sides in &volume.sides {
        for (s, side) in sides.iter().enumerate() {
            // The quarter turn rounds in f32: the light leans 1e-7 off the axis.
            assert!((lum(*side) - expected(s)).abs() <= 1e-3 * expected(s) + 1e-6 * lux, "side {s}: {side}");
        }
    }
    let path = dir.join("out/volume.ktx2");
    let written = write_volume(&path, &volume).unwrap();
    assert_eq!(written, [path.clone(), dir.join("out/volume.json")]);
    let bytes = std::fs::read(&path).unwrap();
    let reader = ktx2::Reader::new(&bytes[..]).unwrap();
    let header = reader.header();
    assert_eq!(header.format, Some(ktx2::Format::E5B9G9R9_UFLOAT_PACK32));
    assert_eq!((header.pixel_width, header.pixel_height, header.pixel_depth), (r.x, 2 * r.y, 3 * r.z));
    let raw = zstd::decode_all(reader.levels().next().unwrap().data).unwrap();
    let texel = |x: u32, t: u32, p: u32| {
        let k = 4 * ((p * 2 * r.y + t) * r.x + x) as usize;
        Format::E5B9G9R9.unpack(u32::from_le_bytes(raw[k..k + 4].try_into().unwrap()))
    };
    for z in 0..r.z {
        for y in 0..r.y {
            for x in 0..r.x {
                for (s, side) in SIDES.iter().enumerate() {
                    let negative = side.min_element() < 0.0;
                    let axis = s / 2;
                    let value = texel(x, y + if negative { r.y } else { 0 }, z + axis as u32 * r.z);
                    let e = expected(s);
                    // E5B9G9R9 keeps 9 bits of mantissa.
                    assert!(
                        (lum(value) - e).abs() <= 4e-3 * e + 1e-6 * lux,
                        "voxel ({x}, {y}, {z}) side {side}: {value}"
                    );
                }
            }
        }
    }
    let info: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.join("out/volume.json")).unwrap()).unwrap();
    assert_eq!(info["transform"], json!({ "translation": [0.5, 0.5, 0.5], "scale": [1.0, 1.0, 1.0] }));
}

/// Voxel centres inside a closed box: their samples all meet back faces, so they are marked and
/// filled from their neighbours, never left black. A double-sided material (Blender's default)
/// shades the box's inside too, but the box still has one.
#[test]
fn voxels_inside_geometry_are_filled_from_their_neighbours() {
    for double_sided in [false, true] {
        let dir = TempDir::new("volume", "inside");
        let mut doc = Doc::default();
        let m = doc.material(0.5, 0.0);
        if double_sided {
            doc.double_sided(m);
        }
        // 4 x 4 x 4 voxels over [0, 4]^3: centres at 0.5, 1.5, ...; the box holds the 8 at 1.5 and 2.5.
        doc.mesh("box", &[cuboid(Vec3::splat(1.0), Vec3::splat(3.0), false, false, m)]);
        let volume = bake(&dir, &doc, &options(UVec3::splat(4), (Vec3::ZERO, Vec3::splat(4.0))), sky).unwrap();
        assert_eq!(volume.inside, 8, "double-sided {double_sided}");
        for (v, state) in volume.state.iter().enumerate() {
            let centre = volume.voxel_center(UVec3::new(v as u32 % 4, v as u32 / 4 % 4, v as u32 / 16));
            let inside = centre.cmpgt(Vec3::ONE).all() && centre.cmplt(Vec3::splat(3.0)).all();
            let want = if inside { TexelState::Filled } else { TexelState::Baked };
            assert!(state.iter().all(|s| *s == want), "voxel {v} at {centre}: {state:?} (double-sided {double_sided})");
            let sides = volume.sides[v];
            assert!(sides.iter().all(|s| lum(*s) > 0.05 * NITS as f64), "voxel {v}: {sides:?} ({double_sided})");
        }
    }
}

/// Bevy's CornellBox as Blender exported it, every material double-sided: the voxel centres inside
/// its two boxes (behind every face plane of one) are found inside, no more and no fewer, and
/// filled from their neighbours. Issue 61: a 4^3 grid reported none inside and left voxel
/// (1, 1, 1), inside the large box, black on all six sides.
#[test]
fn cornell_box_voxels_inside_its_double_sided_boxes_are_found_and_filled() {
    let job = RenderJob { scene: Some(test_data("gltf/bevy/CornellBox.glb")), seed: 3, ..RenderJob::default() };
    let mut loaded = job.load().unwrap();
    let mut boxes: Vec<Vec<[Vec3; 3]>> = Vec::new();
    for p in &loaded.primitives {
        let material = loaded.world.get::<Material>(p.entity).unwrap();
        assert!(material.double_sided, "{:?}: the file's materials are all double-sided", p.mesh_name);
        if matches!(p.mesh_name.as_deref(), Some("large_box" | "small_box")) {
            let mesh = loaded.world.get::<Mesh>(p.entity).unwrap();
            boxes.push((0..mesh.triangle_count()).map(|t| mesh.triangle(t)).collect());
        }
    }
    assert_eq!(boxes.len(), 2);
    let in_a_box =
        |p: Vec3| boxes.iter().any(|faces| faces.iter().all(|[a, b, c]| (p - *a).dot((*b - *a).cross(*c - *a)) < 0.0));
    let opts = VolumeOptions { resolution: UVec3::splat(4), spp: 64, ..VolumeOptions::default() };
    let volume = bake_volume(&mut loaded, &opts, |_| {}).unwrap();
    let at = |v: usize| volume.voxel_center(UVec3::new(v as u32 % 4, v as u32 / 4 % 4, v as u32 / 16));
    let expected: Vec<usize> = (0..64).filter(|&v| in_a_box(at(v))).collect();
    eprintln!("voxels inside the boxes: {expected:?}; voxel (1, 1, 1) at {}", at(21));
    assert!(expected.contains(&21), "voxel (1, 1, 1) at {} lies inside the large box", at(21));
    assert_eq!(volume.inside, expected.len());
    let mean = volume.sides.iter().flatten().map(|s| lum(*s)).sum::<f64>() / (6 * 64) as f64;
    for (v, state) in volume.state.iter().enumerate() {
        let want = if expected.contains(&v) { TexelState::Filled } else { TexelState::Baked };
        assert!(state.iter().all(|s| *s == want), "voxel {v} at {}: {state:?}", at(v));
    }
    for &v in &expected {
        // Filled from the same sides of lit neighbours: a share of the room's mean, never black.
        let sides = volume.sides[v];
        assert!(sides.iter().all(|s| lum(*s) > 0.02 * mean), "voxel {v}: {sides:?} (room mean {mean})");
    }
}

#[test]
fn bad_input_gives_clear_errors() {
    let dir = TempDir::new("volume", "bad");
    let cases = [
        (options(UVec3::new(0, 1, 1), (Vec3::ZERO, Vec3::ONE)), "resolution x = 0 is outside 1..=128"),
        (options(UVec3::ONE, (Vec3::ONE, Vec3::ZERO)), "need finite corners with min < max"),
        (VolumeOptions { spp: 0, ..VolumeOptions::default() }, "spp = 0 is outside 1..=1048576"),
        (VolumeOptions::default(), "nothing to bake: the scene has no geometry to bound the volume; give bounds"),
    ];
    for (opts, says) in cases {
        let err = bake(&dir, &Doc::default(), &opts, sky).unwrap_err();
        assert!(err.to_string().contains(says), "{err}");
    }
    let kelvin = |args: &[&str]| {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_kelvin")).args(args).output().unwrap();
        assert!(!out.status.success(), "{args:?} succeeded");
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let err = kelvin(&["bake", "volume", "no-such.glb", "-o", "never.ktx2", "--resolution", "2,2,2"]);
    assert!(err.contains("no-such.glb: file not found"), "{err}");
    let err = kelvin(&["bake", "volume", "no-such.glb", "-o", "never.exr", "--resolution", "2,2,2"]);
    assert!(err.contains("never.exr: the volume is written as .ktx2"), "{err}");
}

/// Against the irradiance volume Bevy ships (`Example.vxgi.ktx2`, baked in Blender by
/// export-blender-gi for `IrradianceVolumeExample.glb`: a floor of four coloured quadrants under the
/// volume). kelvin bakes the same file, under a white sky, over the box the Bevy example places the
/// volume in. Bevy's probe transform maps its voxel x to world -x, y to world z and z to world y,
/// while the sides stay world axes (its shader samples them with the world normal). Read in the
/// layout Bevy's shader samples, negative sides in the upper half of each slice (as kelvin writes
/// them), the colour each side bounces from the floor, the red-blue chromaticity, follows kelvin's
/// voxel for voxel on every side that sees the floor. Read with positive sides in the upper half
/// (as the doc comment of Bevy's irradiance_volume.rs has it), the down-facing side does not.
#[test]
fn the_layout_matches_bevys_own_volume_side_by_side() {
    use common::files::test_data;
    let bytes = std::fs::read(test_data("bake/bevy/Example.vxgi.ktx2")).unwrap();
    let reader = ktx2::Reader::new(&bytes[..]).unwrap();
    let header = reader.header();
    assert_eq!(header.format, Some(ktx2::Format::E5B9G9R9_UFLOAT_PACK32));
    let (w, h) = (header.pixel_width, header.pixel_height);
    let rb = UVec3::new(w, h / 2, header.pixel_depth / 3);
    assert_eq!(rb, UVec3::new(8, 8, 3));
    let raw = reader.levels().next().unwrap().data.to_vec(); // no supercompression in Bevy's file
    let bevy = |v: UVec3, axis: u32, upper: bool| {
        let (t, p) = (v.y + if upper { rb.y } else { 0 }, v.z + axis * rb.z);
        let k = 4 * ((p * h + t) * w + v.x) as usize;
        Format::E5B9G9R9.unpack(u32::from_le_bytes(raw[k..k + 4].try_into().unwrap()))
    };

    // The example's probe: a [-0.5, 0.5]^3 cube scaled by (42.317566, 44.601563, 16.73776) onto world
    // (-x, z, y), centred at y = 6.544792 (examples/3d/irradiance_volumes.rs, VOXEL_FROM_WORLD).
    let half = Vec3::new(42.317566, 16.73776, 44.601563) / 2.0;
    let centre = Vec3::new(0.0, 6.544792, 0.0);
    let scene = test_data("gltf/bevy/IrradianceVolumeExample.glb");
    let mut loaded = RenderJob { scene: Some(scene), seed: 5, ..RenderJob::default() }.load().unwrap();
    sky(&mut loaded.world);
    let resolution = UVec3::new(rb.x, rb.z, rb.y);
    let opts = VolumeOptions { spp: 64, ..options(resolution, (centre - half, centre + half)) };
    let volume = bake_volume(&mut loaded, &opts, |_| {}).unwrap();
    let kelvin = |v: UVec3, side: usize| {
        let (i, j, k) = (rb.x - 1 - v.x, v.z, v.y);
        volume.sides[((k * resolution.y + j) * resolution.x + i) as usize][side]
    };

    let red_blue = |c: Vec3| (c.x - c.z) as f64 / (c.x + c.y + c.z).max(1e-9) as f64;
    let correlation = |side: usize, upper_if_negative: bool| {
        let (axis, negative) = (side as u32 / 2, SIDES[side].min_element() < 0.0);
        let (mut a, mut b) = (Vec::new(), Vec::new());
        for z in 0..rb.z {
            for y in 0..rb.y {
                for x in 0..rb.x {
                    let v = UVec3::new(x, y, z);
                    a.push(red_blue(kelvin(v, side)));
                    b.push(red_blue(bevy(v, axis, negative == upper_if_negative)));
                }
            }
        }
        correlation(&a, &b)
    };
    let down = SIDES.iter().position(|s| *s == Vec3::NEG_Y).unwrap();
    for (side, dir) in SIDES.iter().enumerate().filter(|(_, d)| d.y <= 0.0) {
        let (shader, doc) = (correlation(side, true), correlation(side, false));
        assert!(
            shader > 0.8 && shader > doc,
            "side {dir}: correlation {shader} in the shader's layout, {doc} in the doc's"
        );
        if side == down {
            assert!(shader > 0.9 && doc.abs() < 0.2, "down: {shader} against {doc}");
        }
    }
}

/// Pearson's correlation of two samples.
fn correlation(a: &[f64], b: &[f64]) -> f64 {
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let (ma, mb) = (mean(a), mean(b));
    let cov: f64 = a.iter().zip(b).map(|(x, y)| (x - ma) * (y - mb)).sum();
    let var = |v: &[f64], m: f64| v.iter().map(|x| (x - m) * (x - m)).sum::<f64>();
    cov / (var(a, ma) * var(b, mb)).sqrt()
}

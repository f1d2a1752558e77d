//! `kelvin bake volume`: ambient cubes against closed forms (a uniform sky on every side; light from
//! +X only on the +X side alone, read face by face from the KTX2 file in Bevy's layout), voxels
//! inside geometry filled from their neighbours, bad input.

mod common;

use glam::{UVec3, Vec3};
use kelvin::bake::ktx2::Format;
use kelvin::bake::volume::SIDES;
use kelvin::bake::{BakeError, IrradianceVolume, TexelState, VolumeOptions, bake_volume, write_volume};
use kelvin::light::UniformInfiniteLight;
use kelvin::render::job::RenderJob;
use serde_json::json;

use common::files::TempDir;
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
/// filled from their neighbours, never left black.
#[test]
fn voxels_inside_geometry_are_filled_from_their_neighbours() {
    let dir = TempDir::new("volume", "inside");
    let mut doc = Doc::default();
    let m = doc.material(0.5, 0.0);
    // 4 x 4 x 4 voxels over [0, 4]^3: centres at 0.5, 1.5, ...; the box holds the 8 at 1.5 and 2.5.
    doc.mesh("box", &[cuboid(Vec3::splat(1.0), Vec3::splat(3.0), false, false, m)]);
    let volume = bake(&dir, &doc, &options(UVec3::splat(4), (Vec3::ZERO, Vec3::splat(4.0))), sky).unwrap();
    assert_eq!(volume.inside, 8);
    for (v, state) in volume.state.iter().enumerate() {
        let centre = volume.voxel_center(UVec3::new(v as u32 % 4, v as u32 / 4 % 4, v as u32 / 16));
        let inside = centre.cmpgt(Vec3::ONE).all() && centre.cmplt(Vec3::splat(3.0)).all();
        let want = if inside { TexelState::Filled } else { TexelState::Baked };
        assert!(state.iter().all(|s| *s == want), "voxel {v} at {centre}: {state:?}");
        assert!(volume.sides[v].iter().all(|s| lum(*s) > 0.05 * NITS as f64), "voxel {v}: {:?}", volume.sides[v]);
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

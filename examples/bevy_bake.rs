//! Baked light for a Bevy app: bakes lightmaps and an irradiance volume for Bevy's CornellBox model
//! (`tests/data/gltf/bevy/CornellBox.glb`, the model of Bevy's lightmaps example) and prints where
//! each file went and what a Bevy 0.20 app sets on which entity.
//! `cargo run --release --example bevy_bake [OUT_DIR]` (default `target/bevy_bake`).
//!
//! The files are what Bevy loads as they are (its `ktx2` and `zstd_rust` features, both in its
//! default `3d`): a lightmap per mesh (B10G11R11_UFLOAT KTX2) and a 3D E5B9G9R9_UFLOAT KTX2 of
//! ambient cubes. Texels are nit, Bevy's own units, so `lightmap_exposure` and the volume's
//! `intensity` are 1; the camera's exposure decides how bright the baked light looks (the index's
//! `camera_ev100`), and emissive materials follow it only with `emissive_exposure_weight` 1.

use std::path::PathBuf;

use glam::UVec3;
use kelvin::bake::{
    BakedLight, LIGHTMAPS_JSON, LightmapOptions, VolumeOptions, bake_lightmaps, bake_volume, write_lightmaps,
    write_volume,
};
use kelvin::render::job::RenderJob;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let out = std::env::args().nth(1).map_or_else(|| root.join("target/bevy_bake"), PathBuf::from);
    let scene = root.join("tests/data/gltf/bevy/CornellBox.glb");
    let job = RenderJob { scene: Some(scene), ..RenderJob::default() };

    // Direct light baked in (the default): the box's only light is its emissive quad, which Bevy
    // does not light with, so nothing real-time draws it.
    let opts = LightmapOptions { size: 128, spp: 64, light: BakedLight::All, ..LightmapOptions::default() };
    let report = bake_lightmaps(&mut job.load()?, &opts, |_| {})?;
    let dir = out.join("lightmaps");
    write_lightmaps(&dir, &report, &opts)?;
    println!("lightmaps ({:.2} s), in {}:", report.stats.seconds, dir.display());
    for map in &report.lightmaps {
        let mesh = map.mesh_name.as_deref().unwrap_or(&map.name);
        println!(
            "  on every entity whose GltfMeshName is \"{mesh}\" (Bevy names them \"{mesh}.<material>\"):\n    \
             Lightmap {{ image: asset_server.load(\"lightmaps/{}.ktx2\"), uv_rect: Rect::new(0.0, 0.0, 1.0, 1.0), \
             bicubic_sampling: false }}, and lightmap_exposure = 1.0 on their StandardMaterial",
            map.name
        );
    }
    let index: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.join(LIGHTMAPS_JSON))?)?;
    match index["camera_ev100"].as_f64() {
        Some(ev100) => {
            println!("  camera: Exposure {{ ev100: {ev100:.2} }} (Bevy's default 9.7 shows this room black)")
        }
        None => println!("  camera: nothing was lit; no exposure to suggest"),
    }
    println!(
        "  emissive materials (the lamp): emissive_exposure_weight = 1.0, so that they follow the exposure as \
         the baked light does"
    );
    println!(
        "  --light all: affects_lightmapped_mesh_diffuse: false on Bevy's point, spot and directional lights the \
         bake saw (else their diffuse light counts twice); --light indirect: leave them true"
    );

    let opts = VolumeOptions { resolution: UVec3::splat(8), spp: 128, ..VolumeOptions::default() };
    let volume = bake_volume(&mut job.load()?, &opts, |_| {})?;
    let path = out.join("volume.ktx2");
    write_volume(&path, &volume)?;
    let (t, s) = (volume.center(), volume.scale());
    println!(
        "irradiance volume ({:.2} s, {} voxels inside geometry, filled from their neighbours): {}",
        volume.stats.seconds,
        volume.inside,
        path.display()
    );
    println!(
        "  spawn (LightProbe, IrradianceVolume {{ voxels: asset_server.load(\"volume.ktx2\"), intensity: 1.0, \
         ..default() }}, Transform::from_xyz({}, {}, {}).with_scale(Vec3::new({}, {}, {})))",
        t.x, t.y, t.z, s.x, s.y, s.z
    );
    Ok(())
}

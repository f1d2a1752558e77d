//! `kelvin bake lightmaps SCENE -o DIR [--size N] [--spp N] [--time SECONDS] [--max-depth N]
//! [--light all|indirect] [--seed S] [--threads T]`: a lightmap per mesh with TEXCOORD_1; `kelvin bake volume SCENE -o
//! FILE.ktx2 --resolution RX,RY,RZ [--bounds X0,Y0,Z0,X1,Y1,Z1] [...]`: an irradiance volume
//! (`kelvin::bake`).

use std::path::PathBuf;

use clap::Subcommand;
use kelvin::bake::{
    self, BakedLight, LightmapOptions, VolumeOptions, bake_lightmaps, bake_volume, write_lightmaps, write_volume,
};
use kelvin::render::job::{self, RenderJob};
use kelvin::render::path::PathDepth;

use super::render::progress_bar;
use super::{CliError, values};

#[derive(clap::Args)]
pub struct BakeArgs {
    #[command(subcommand)]
    command: BakeCommand,
}

#[derive(Subcommand)]
enum BakeCommand {
    /// Lightmaps for Bevy and other engines: per mesh with TEXCOORD_1, DIR/<mesh>.exr (linear) and
    /// DIR/<mesh>.ktx2 (B10G11R11_UFLOAT, zstd), and DIR/lightmaps.json. A texel is the irradiance
    /// there over pi (what a white Lambertian surface reflects), in nit.
    Lightmaps(LightmapArgs),
    /// An irradiance volume for Bevy's IrradianceVolume: a voxel grid of ambient cubes (each side the
    /// irradiance over pi about its axis, in nit) as a 3D KTX2 (E5B9G9R9_UFLOAT, zstd, Bevy's
    /// layout), and FILE.json with the light probe's transform.
    Volume(VolumeArgs),
}

#[derive(clap::Args)]
pub struct VolumeArgs {
    /// glTF scene (.gltf or .glb).
    scene: PathBuf,
    /// Output .ktx2 file (FILE.json is written beside it).
    #[arg(short, long)]
    output: PathBuf,
    /// Voxels along x, y and z.
    #[arg(long, value_name = "RX,RY,RZ", value_parser = values::resolution)]
    resolution: glam::UVec3,
    /// The box the grid fills (default: the scene's geometry).
    #[arg(long, value_name = "X0,Y0,Z0,X1,Y1,Z1", value_parser = values::bounds)]
    bounds: Option<(glam::Vec3, glam::Vec3)>,
    /// Paths per voxel side (per pass, with --time).
    #[arg(long, default_value_t = 256, value_parser = values::whole(job::SPP))]
    spp: u32,
    /// Bake passes of --spp paths per side until this many seconds have passed (at least one).
    #[arg(long, value_name = "SECONDS", value_parser = values::seconds)]
    time: Option<f64>,
    /// Surfaces after the voxel's a path may reach (1 = direct light only).
    #[arg(long, default_value_t = PathDepth::DEFAULT.max_depth, value_parser = values::whole(job::DEPTH))]
    max_depth: u32,
    /// All light, or bounced light only.
    #[arg(long, value_enum, default_value = "all")]
    light: BakedLight,
    /// Seed of the random numbers.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Worker threads (default: all cores). The volume is bit-identical for any count.
    #[arg(long, value_parser = values::threads())]
    threads: Option<usize>,
}

#[derive(clap::Args)]
pub struct LightmapArgs {
    /// glTF scene (.gltf or .glb) whose meshes carry lightmap uvs (TEXCOORD_1).
    scene: PathBuf,
    /// Output folder (created): the lightmaps and lightmaps.json.
    #[arg(short, long)]
    output: PathBuf,
    /// Side of each lightmap, texels.
    #[arg(long, default_value_t = 256, value_parser = values::whole(bake::SIZE))]
    size: u32,
    /// Paths per texel (per pass, with --time).
    #[arg(long, default_value_t = 128, value_parser = values::whole(job::SPP))]
    spp: u32,
    /// Bake passes of --spp paths per texel until this many seconds have passed (at least one).
    #[arg(long, value_name = "SECONDS", value_parser = values::seconds)]
    time: Option<f64>,
    /// Surfaces after the texel's a path may reach (1 = direct light only).
    #[arg(long, default_value_t = PathDepth::DEFAULT.max_depth, value_parser = values::whole(job::DEPTH))]
    max_depth: u32,
    /// All light (direct and bounced: a fully baked scene), or bounced light only (for direct
    /// light that stays real-time).
    #[arg(long, value_enum, default_value = "all")]
    light: BakedLight,
    /// Seed of the random numbers.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Worker threads (default: all cores). Lightmaps are bit-identical for any count.
    #[arg(long, value_parser = values::threads())]
    threads: Option<usize>,
}

pub fn run(args: BakeArgs) -> Result<(), CliError> {
    match args.command {
        BakeCommand::Lightmaps(args) => lightmaps(args),
        BakeCommand::Volume(args) => volume(args),
    }
}

/// Loads `scene` as `kelvin render` would, printing the loader's warnings and the summary.
fn load(scene: &std::path::Path, seed: u64, threads: Option<usize>) -> Result<job::LoadedJob, CliError> {
    if let Some(t) = threads {
        rayon::ThreadPoolBuilder::new().num_threads(t).build_global()?;
    }
    let loaded = RenderJob { scene: Some(scene.to_path_buf()), seed, ..RenderJob::default() }.load()?;
    for w in &loaded.warnings {
        eprintln!("warning: {w}");
    }
    if let Some(summary) = &loaded.summary {
        eprintln!("{summary}");
    }
    Ok(loaded)
}

fn volume(args: VolumeArgs) -> Result<(), CliError> {
    if args.output.extension().is_none_or(|e| !e.eq_ignore_ascii_case("ktx2")) {
        return Err(format!("{}: the volume is written as .ktx2", args.output.display()).into());
    }
    let opts = VolumeOptions {
        resolution: args.resolution,
        spp: args.spp,
        depth: PathDepth { max_depth: args.max_depth, ..PathDepth::DEFAULT },
        light: args.light,
        bounds: args.bounds,
        time: args.time,
    };
    let mut loaded = load(&args.scene, args.seed, args.threads)?;
    let bar = progress_bar();
    let baked = bake_volume(&mut loaded, &opts, |f| bar.set_position((f * 1000.0) as u64));
    bar.finish_and_clear();
    let volume = baked.map_err(|e| format!("{}: {e}", args.scene.display()))?;
    for w in &volume.stats.report.warnings {
        eprintln!("warning: {w}");
    }
    let written = write_volume(&args.output, &volume)?;
    let r = volume.resolution;
    println!(
        "baked a {}x{}x{} volume at {} spp in {:.3} s ({} voxels inside geometry, filled); Transform: translation {}, scale {}",
        r.x,
        r.y,
        r.z,
        volume.stats.spp,
        volume.stats.seconds,
        volume.inside,
        volume.center(),
        volume.scale()
    );
    for path in written {
        println!("wrote {}", path.display());
    }
    Ok(())
}

fn lightmaps(args: LightmapArgs) -> Result<(), CliError> {
    let opts = LightmapOptions {
        size: args.size,
        spp: args.spp,
        depth: PathDepth { max_depth: args.max_depth, ..PathDepth::DEFAULT },
        light: args.light,
        time: args.time,
        ..LightmapOptions::default()
    };
    let mut loaded = load(&args.scene, args.seed, args.threads)?;
    let bar = progress_bar();
    let baked = bake_lightmaps(&mut loaded, &opts, |f| bar.set_position((f * 1000.0) as u64));
    bar.finish_and_clear();
    let report = baked.map_err(|e| format!("{}: {e}", args.scene.display()))?;
    for s in &report.skipped {
        eprintln!("skipped: {s}");
    }
    for w in &report.warnings {
        eprintln!("warning: {w}");
    }
    let written = write_lightmaps(&args.output, &report, &opts)?;
    let stats = &report.stats;
    println!(
        "baked {} lightmaps of {}x{} at {} spp in {:.3} s: {:.2} M paths/s, {:.2} M shadow rays/s, {:.2} M BSDF rays/s",
        report.lightmaps.len(),
        args.size,
        args.size,
        stats.spp,
        stats.seconds,
        stats.camera_samples as f64 / stats.seconds.max(1e-9) / 1e6,
        stats.shadow_rays as f64 / stats.seconds.max(1e-9) / 1e6,
        stats.bsdf_rays as f64 / stats.seconds.max(1e-9) / 1e6,
    );
    for path in written {
        println!("wrote {}", path.display());
    }
    Ok(())
}

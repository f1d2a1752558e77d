//! `kelvin bake lightmaps SCENE -o DIR [--size N] [--spp N] [--max-depth N] [--light all|indirect]
//! [--seed S] [--threads T]`: a lightmap per mesh with TEXCOORD_1 (`kelvin::bake`).

use std::path::PathBuf;

use clap::Subcommand;
use kelvin::bake::{self, BakedLight, LightmapOptions, bake_lightmaps, write_lightmaps};
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
    /// Paths per texel.
    #[arg(long, default_value_t = 128, value_parser = values::whole(job::SPP))]
    spp: u32,
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
    }
}

fn lightmaps(args: LightmapArgs) -> Result<(), CliError> {
    if let Some(t) = args.threads {
        rayon::ThreadPoolBuilder::new().num_threads(t).build_global()?;
    }
    let job = RenderJob { scene: Some(args.scene.clone()), seed: args.seed, ..RenderJob::default() };
    let opts = LightmapOptions {
        size: args.size,
        spp: args.spp,
        depth: PathDepth { max_depth: args.max_depth, ..PathDepth::DEFAULT },
        light: args.light,
        ..LightmapOptions::default()
    };
    let mut loaded = job.load()?;
    for w in &loaded.warnings {
        eprintln!("warning: {w}");
    }
    if let Some(summary) = &loaded.summary {
        eprintln!("{summary}");
    }
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
        args.spp,
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

//! `kelvin bake lightmaps SCENE -o DIR [--size N | --texels-per-unit D] [--spp N] [...]`: a
//! lightmap per mesh with TEXCOORD_1; `kelvin bake volume SCENE -o FILE.ktx2 --resolution RX,RY,RZ
//! [--bounds X0,Y0,Z0,X1,Y1,Z1 | --node NAME] [...]`: an irradiance volume (`kelvin::bake`). Both
//! take `--env`/`--sky` as `kelvin render` does, and split over machines with `--part K/N` (each
//! part's sums into the output's parts folder) and `--merge` (the finished bake, bit for bit).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use clap::Subcommand;
use indicatif::{ProgressBar, ProgressStyle};
use kelvin::bake::{
    self, BakePart, BakedLight, LightmapOptions, Part, Progress, VolumeOptions, bake_lightmaps, bake_lightmaps_part,
    bake_volume, bake_volume_part, check_provenance, merge_lightmaps, merge_volume, node_bounds, write_lightmaps,
    write_volume,
};
use kelvin::render::film_io::write_file;
use kelvin::render::job::{self, LoadedJob, RenderJob};
use kelvin::render::path::PathDepth;
use kelvin::rng::Pattern;
use serde_json::json;

use super::render::LightingArgs;
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

/// What both bakes take.
#[derive(clap::Args)]
struct CommonArgs {
    /// Bake passes of --spp paths per texel (or voxel side) until this many seconds have passed
    /// (at least one).
    #[arg(long, value_name = "SECONDS", value_parser = values::seconds)]
    time: Option<f64>,
    /// Surfaces after the texel's (or voxel's) a path may reach (1 = direct light only).
    #[arg(long, default_value_t = PathDepth::DEFAULT.max_depth, value_parser = values::whole(job::DEPTH))]
    max_depth: u32,
    /// All light (direct and bounced: a fully baked scene), or bounced light only (for direct
    /// light that stays real-time).
    #[arg(long, value_enum, default_value = "all")]
    light: BakedLight,
    /// Seed of the random numbers.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Random numbers of the paths: Owen-scrambled Sobol (stratified) or independent.
    #[arg(long, value_enum, default_value = "sobol")]
    pattern: Pattern,
    /// Worker threads (default: all cores). The bake is bit-identical for any count.
    #[arg(long, value_parser = values::threads())]
    threads: Option<usize>,
    #[command(flatten)]
    lighting: LightingArgs,
    /// Bake only part K of N of the texels (or voxel sides), with every sample the whole bake
    /// gives them, into the output's parts folder; `--merge` joins the N parts.
    #[arg(long, value_name = "K/N", conflicts_with_all = ["merge", "time"])]
    part: Option<Part>,
    /// Join the parts baked with --part (same scene and options, checked) into the finished
    /// output, bit for bit the bake unsplit; then remove the parts folder.
    #[arg(long)]
    merge: bool,
}

#[derive(clap::Args)]
pub struct VolumeArgs {
    /// glTF scene (.gltf or .glb).
    scene: PathBuf,
    /// Output .ktx2 file (FILE.json is written beside it; parts go to FILE.parts/).
    #[arg(short, long)]
    output: PathBuf,
    /// Voxels along x, y and z.
    #[arg(long, value_name = "RX,RY,RZ", value_parser = values::resolution)]
    resolution: glam::UVec3,
    /// The box the grid fills (default: the scene's geometry).
    #[arg(long, value_name = "X0,Y0,Z0,X1,Y1,Z1", value_parser = values::bounds, conflicts_with = "node")]
    bounds: Option<(glam::Vec3, glam::Vec3)>,
    /// The grid fills the bounding box of the meshes the nodes of this name place.
    #[arg(long, value_name = "NAME")]
    node: Option<String>,
    /// Paths per voxel side (per pass, with --time).
    #[arg(long, default_value_t = 256, value_parser = values::whole(job::SPP))]
    spp: u32,
    #[command(flatten)]
    common: CommonArgs,
}

#[derive(clap::Args)]
pub struct LightmapArgs {
    /// glTF scene (.gltf or .glb) whose meshes carry lightmap uvs (TEXCOORD_1).
    scene: PathBuf,
    /// Output folder (created): the lightmaps and lightmaps.json (parts go to DIR/parts/).
    #[arg(short, long)]
    output: PathBuf,
    /// Side of each lightmap, texels (default 256); with --texels-per-unit, the largest side.
    #[arg(long, value_parser = values::whole(bake::SIZE))]
    size: Option<u32>,
    /// Texels per metre along the surface: each mesh's side follows from its area and its uv1
    /// charts' share of the atlas, so texels are about the same size everywhere.
    #[arg(long, value_name = "D", value_parser = values::finite_in(1e-6, 1e6))]
    texels_per_unit: Option<f32>,
    /// Paths per texel (per pass, with --time).
    #[arg(long, default_value_t = 128, value_parser = values::whole(job::SPP))]
    spp: u32,
    #[command(flatten)]
    common: CommonArgs,
}

pub fn run(args: BakeArgs) -> Result<(), CliError> {
    match args.command {
        BakeCommand::Lightmaps(args) => lightmaps(args),
        BakeCommand::Volume(args) => volume(args),
    }
}

#[derive(clap::Parser)]
#[command(name = "kelvin bake")]
struct BakeCommandLine {
    #[command(flatten)]
    args: BakeArgs,
}

/// `kelvin bake` arguments (`lightmaps ...` or `volume ...`) as the command line parses them:
/// a manifest's bake job means what the command means. The error is clap's first line.
pub(super) fn parse(args: &[String]) -> Result<BakeArgs, String> {
    let argv = std::iter::once("kelvin-bake".to_owned()).chain(args.iter().cloned());
    clap::Parser::try_parse_from(argv).map(|c: BakeCommandLine| c.args).map_err(|e| {
        let text = e.to_string();
        text.lines().next().unwrap_or_default().trim_start_matches("error: ").to_owned()
    })
}

/// The clap definition of `kelvin bake KIND` (lightmaps or volume), for the manifest's schema.
pub(super) fn command(kind: &str) -> clap::Command {
    let all = <BakeCommandLine as clap::CommandFactory>::command();
    all.find_subcommand(kind).cloned().unwrap_or(all)
}

impl BakeArgs {
    /// Where the finished bake goes, and the folder its parts go to.
    pub(super) fn output(&self) -> (&Path, PathBuf) {
        match &self.command {
            BakeCommand::Lightmaps(a) => (&a.output, a.output.join("parts")),
            BakeCommand::Volume(a) => (&a.output, a.output.with_extension("parts")),
        }
    }

    fn scene_and_common(&self) -> (&Path, &CommonArgs) {
        match &self.command {
            BakeCommand::Lightmaps(a) => (a.scene.as_path(), &a.common),
            BakeCommand::Volume(a) => (a.scene.as_path(), &a.common),
        }
    }

    /// The files the bake reads by name (scene, environment map) and those the scene references.
    pub(super) fn input_files(&self) -> Vec<PathBuf> {
        let (scene, common) = self.scene_and_common();
        let referenced = kelvin::scene::gltf::referenced_files(scene);
        std::iter::once(scene.to_path_buf()).chain(common.lighting.env.clone()).chain(referenced).collect()
    }

    /// Whether the bake is finished: its index file (lightmaps.json, or the volume's .json), which is
    /// written last, exists and records this bake's provenance (options, kelvin's version, and the
    /// inputs: each file it lists hashed again now; the program may differ, as for renders).
    /// Otherwise, for an existing index, why it is not this bake's.
    pub(super) fn finished(&self) -> (bool, Option<String>) {
        let index = index_path(&self.command);
        if !index.is_file() {
            return (false, None);
        }
        let recorded = std::fs::read(&index)
            .map_err(|e| e.to_string())
            .and_then(|b| serde_json::from_slice::<serde_json::Value>(&b).map_err(|e| e.to_string()));
        let mut recorded = match recorded {
            Ok(json) => json.get("provenance").cloned().unwrap_or_default(),
            Err(e) => return (false, Some(format!("{} does not read back: {e}", index.display()))),
        };
        let (scene, common) = self.scene_and_common();
        let listed = recorded.get("inputs").and_then(|i| i.as_object()).map(|i| i.keys().cloned().collect());
        let listed: Vec<String> = listed.unwrap_or_default();
        let inputs = match super::render::inputs_now(Some(scene), common.lighting.env.as_deref(), listed.iter()) {
            Ok(inputs) => inputs,
            Err(e) => return (false, Some(e)),
        };
        let mut wanted = match &self.command {
            BakeCommand::Lightmaps(a) => a.provenance(inputs),
            BakeCommand::Volume(a) => a.provenance(inputs),
        };
        for p in [&mut recorded, &mut wanted] {
            if let Some(p) = p.as_object_mut() {
                p.remove("program");
            }
        }
        match check_provenance(&wanted, &recorded) {
            Ok(()) => (true, None),
            Err(field) => (false, Some(format!("{} records another bake: {field}", index.display()))),
        }
    }
}

impl CommonArgs {
    /// Loads `scene` as `kelvin render` would, printing the loader's warnings and the summary.
    fn load(&self, scene: &Path) -> Result<LoadedJob, CliError> {
        if let Some(t) = self.threads {
            rayon::ThreadPoolBuilder::new().num_threads(t).build_global()?;
        }
        let job = RenderJob {
            scene: Some(scene.to_path_buf()),
            seed: self.seed,
            pattern: self.pattern,
            ..RenderJob::default()
        };
        let loaded = self.lighting.apply(job).load()?;
        for w in &loaded.warnings {
            eprintln!("warning: {w}");
        }
        if let Some(summary) = &loaded.summary {
            eprintln!("{summary}");
        }
        Ok(loaded)
    }

    fn depth(&self) -> PathDepth {
        PathDepth { max_depth: self.max_depth, ..PathDepth::DEFAULT }
    }

    /// What a part (and the finished bake's index) records about how it was made, `settings` the
    /// command's own and `inputs` the digests of the files read, as read
    /// ([`kelvin::provenance::Inputs::entries`]): a merge compares all of it, the program included.
    fn provenance(&self, settings: serde_json::Value, inputs: BTreeMap<String, String>) -> serde_json::Value {
        json!({
            "kelvin": env!("CARGO_PKG_VERSION"),
            "program": kelvin::provenance::program(),
            "inputs": inputs,
            "settings": {
                "command": settings,
                "time": self.time,
                "max_depth": self.max_depth,
                "light": format!("{:?}", self.light),
                "seed": self.seed,
                "pattern": format!("{:?}", self.pattern),
                "env_intensity": self.lighting.env_intensity,
                "sky": self.lighting.sky,
                "sky_intensity": self.lighting.sky_intensity,
            },
        })
    }
}

/// A progress bar of paths traced (cells x spp).
fn samples_bar() -> ProgressBar {
    let bar = ProgressBar::new(0);
    let style = "{bar:40} {percent:>3}% {human_pos}/{human_len} paths (texels x spp) {elapsed_precise} eta {eta}";
    bar.set_style(ProgressStyle::with_template(style).expect("valid template"));
    bar
}

fn show(bar: &ProgressBar, p: Progress) {
    bar.set_length(p.of);
    bar.set_position((p.fraction as f64 * p.of as f64) as u64);
}

/// The file part `part` is written to in `folder`.
fn part_path(folder: &Path, part: Part) -> PathBuf {
    folder.join(format!("part-{}-of-{}.kbake", part.index + 1, part.count))
}

/// Writes `part` with `provenance` into `folder` (created).
fn write_part(folder: &Path, mut part: BakePart, provenance: serde_json::Value) -> Result<(), CliError> {
    std::fs::create_dir_all(folder).map_err(super::exit::io(folder.display()))?;
    let path = part_path(folder, part.part());
    part.set_provenance(provenance);
    write_file(&path, &path.display().to_string(), &part.to_bytes())?;
    let p = part.part();
    println!("baked part {} of {}: wrote {} (join the parts with --merge)", p.index + 1, p.count, path.display());
    Ok(())
}

/// The parts to merge from `folder`: every part file, each checked to have been made as
/// `provenance` says (and whole: its checksum), of the one split (N) whose every part is there;
/// parts of another split, left by an earlier run split otherwise, are ignored with a warning.
fn read_parts(folder: &Path, provenance: &serde_json::Value) -> Result<Vec<BakePart>, CliError> {
    let entries = std::fs::read_dir(folder).map_err(|e| format!("{}: no parts to merge: {e}", folder.display()))?;
    let mut splits: BTreeMap<u32, Vec<BakePart>> = BTreeMap::new();
    for entry in entries {
        let path = entry.map_err(super::exit::io(folder.display()))?.path();
        if path.extension().is_none_or(|e| e != "kbake") {
            continue;
        }
        let what = path.display().to_string();
        let bytes = std::fs::read(&path).map_err(super::exit::io(&what))?;
        let part = BakePart::from_bytes(&bytes, &what)?;
        check_provenance(provenance, part.provenance())
            .map_err(|f| format!("{what} was not made by this bake (scene, options or build): {f}"))?;
        splits.entry(part.part().count).or_default().push(part);
    }
    let complete = |parts: &Vec<BakePart>, n: u32| {
        let mut have: Vec<u32> = parts.iter().map(|p| p.part().index).collect();
        have.sort_unstable();
        have.dedup();
        have.len() == n as usize
    };
    let whole: Vec<u32> = splits.iter().filter(|(n, p)| complete(p, **n)).map(|(n, _)| *n).collect();
    let Some(&n) = whole.first().filter(|_| whole.len() == 1 || splits.len() == 1) else {
        // None complete (the merge names the missing cells), or several: all go to the merge, which refuses them.
        return Ok(splits.into_values().flatten().collect());
    };
    for (other, parts) in splits.iter().filter(|(other, _)| **other != n) {
        eprintln!(
            "warning: {}: {} parts of a split into {other} ignored (merging the split into {n})",
            folder.display(),
            parts.len()
        );
    }
    Ok(splits.remove(&n).unwrap_or_default())
}

/// Whether `part` is already baked in `folder` as `provenance` says (whole, and made by this bake):
/// a rerun of a split bake resumes per part.
fn part_done(folder: &Path, part: kelvin::bake::Part, provenance: &serde_json::Value) -> bool {
    let path = part_path(folder, part);
    let Ok(bytes) = std::fs::read(&path) else { return false };
    match BakePart::from_bytes(&bytes, &path.display().to_string()) {
        Ok(p) => p.part() == part && check_provenance(provenance, p.provenance()).is_ok(),
        Err(e) => {
            eprintln!("warning: {e}; baking it again");
            false
        }
    }
}

/// Whether the `--part` asked for is already baked (then said so): nothing to do.
fn skip_done_part(common: &CommonArgs, folder: &Path, provenance: &serde_json::Value) -> bool {
    let Some(part) = common.part.filter(|p| part_done(folder, *p, provenance)) else { return false };
    println!("part {} of {} is already baked in {}: kept", part.index + 1, part.count, folder.display());
    true
}

/// The file a finished bake writes last: lightmaps.json, or the volume's .json.
fn index_path(command: &BakeCommand) -> PathBuf {
    match command {
        BakeCommand::Lightmaps(a) => a.output.join(bake::LIGHTMAPS_JSON),
        BakeCommand::Volume(a) => a.output.with_extension("json"),
    }
}

/// Adds `provenance` to the index file `index` the library wrote (rewritten under a temporary name
/// and renamed, so a stop in between leaves an index without it: not finished, baked again).
fn record_provenance(index: &Path, provenance: serde_json::Value) -> Result<(), CliError> {
    let what = index.display().to_string();
    let mut json: serde_json::Value = serde_json::from_slice(&std::fs::read(index).map_err(super::exit::io(&what))?)?;
    json["provenance"] = provenance;
    let text = serde_json::to_string_pretty(&json)? + "\n";
    write_file(index, &what, text.as_bytes())?;
    Ok(())
}

impl VolumeArgs {
    /// What the volume's parts and index record about how it was made.
    fn provenance(&self, inputs: BTreeMap<String, String>) -> serde_json::Value {
        let settings = json!({
            "volume": self.resolution.to_array(),
            "bounds": self.bounds.map(|(lo, hi)| [lo.to_array(), hi.to_array()]),
            "node": self.node,
            "spp": self.spp,
        });
        self.common.provenance(settings, inputs)
    }
}

impl LightmapArgs {
    /// What the lightmaps' parts and index record about how they were made.
    fn provenance(&self, inputs: BTreeMap<String, String>) -> serde_json::Value {
        let opts = self.options();
        let settings = json!({
            "lightmaps": opts.size,
            "texels_per_unit": opts.texels_per_unit,
            "spp": opts.spp,
            "margin": opts.margin,
        });
        self.common.provenance(settings, inputs)
    }

    fn options(&self) -> LightmapOptions {
        let common = &self.common;
        LightmapOptions {
            size: self.size.unwrap_or(if self.texels_per_unit.is_some() { *bake::SIZE.end() } else { 256 }),
            texels_per_unit: self.texels_per_unit,
            spp: self.spp,
            depth: common.depth(),
            light: common.light,
            time: common.time,
            ..LightmapOptions::default()
        }
    }
}

fn volume(args: VolumeArgs) -> Result<(), CliError> {
    if args.output.extension().is_none_or(|e| !e.eq_ignore_ascii_case("ktx2")) {
        return Err(format!("{}: the volume is written as .ktx2", args.output.display()).into());
    }
    let common = &args.common;
    let mut loaded = common.load(&args.scene)?;
    let bounds = match &args.node {
        Some(node) => Some(node_bounds(&loaded, node).map_err(|e| format!("--node: {e}"))?),
        None => args.bounds,
    };
    let opts = VolumeOptions {
        resolution: args.resolution,
        spp: args.spp,
        depth: common.depth(),
        light: common.light,
        bounds,
        time: common.time,
    };
    let provenance = args.provenance(loaded.inputs.entries());
    let folder = args.output.with_extension("parts");
    if skip_done_part(common, &folder, &provenance) {
        return Ok(());
    }
    let scene = args.scene.display();
    let volume = if common.merge {
        let parts = read_parts(&folder, &provenance)?;
        merge_volume(&mut loaded, &opts, parts).map_err(|e| format!("{}: {e}", folder.display()))?
    } else {
        let bar = samples_bar();
        let progress = |p| show(&bar, p);
        if let Some(part) = common.part {
            let baked = bake_volume_part(&mut loaded, &opts, part, progress);
            bar.finish_and_clear();
            let baked = baked.map_err(|e| format!("{scene}: {e}"))?;
            return write_part(&folder, baked, provenance);
        }
        let baked = bake_volume(&mut loaded, &opts, progress);
        bar.finish_and_clear();
        baked.map_err(|e| format!("{scene}: {e}"))?
    };
    for w in &volume.stats.report.warnings {
        eprintln!("warning: {w}");
    }
    let written = write_volume(&args.output, &volume)?;
    record_provenance(&args.output.with_extension("json"), provenance)?;
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
    if common.merge {
        remove_parts(&folder);
    }
    Ok(())
}

fn lightmaps(args: LightmapArgs) -> Result<(), CliError> {
    let common = &args.common;
    let opts = args.options();
    let mut loaded = common.load(&args.scene)?;
    // The digests of the files as the load read them.
    let provenance = args.provenance(loaded.inputs.entries());
    let folder = args.output.join("parts");
    if skip_done_part(common, &folder, &provenance) {
        return Ok(());
    }
    let scene = args.scene.display();
    let report = if common.merge {
        let parts = read_parts(&folder, &provenance)?;
        merge_lightmaps(&mut loaded, &opts, parts).map_err(|e| format!("{}: {e}", folder.display()))?
    } else {
        let bar = samples_bar();
        let progress = |p| show(&bar, p);
        if let Some(part) = common.part {
            let baked = bake_lightmaps_part(&mut loaded, &opts, part, progress);
            bar.finish_and_clear();
            let baked = baked.map_err(|e| format!("{scene}: {e}"))?;
            return write_part(&folder, baked, provenance);
        }
        let baked = bake_lightmaps(&mut loaded, &opts, progress);
        bar.finish_and_clear();
        baked.map_err(|e| format!("{scene}: {e}"))?
    };
    for s in &report.skipped {
        eprintln!("skipped: {s}");
    }
    for w in &report.warnings {
        eprintln!("warning: {w}");
    }
    let written = write_lightmaps(&args.output, &report, &opts)?;
    record_provenance(&args.output.join(bake::LIGHTMAPS_JSON), provenance)?;
    let stats = &report.stats;
    let sides: Vec<String> = report.lightmaps.iter().map(|m| format!("{} {}", m.name, m.size)).collect();
    println!(
        "baked {} lightmaps ({}) at {} spp in {:.3} s: {:.2} M paths/s, {:.2} M shadow rays/s, {:.2} M BSDF rays/s",
        report.lightmaps.len(),
        sides.join(", "),
        stats.spp,
        stats.seconds,
        stats.camera_samples as f64 / stats.seconds.max(1e-9) / 1e6,
        stats.shadow_rays as f64 / stats.seconds.max(1e-9) / 1e6,
        stats.bsdf_rays as f64 / stats.seconds.max(1e-9) / 1e6,
    );
    for path in written {
        println!("wrote {}", path.display());
    }
    if common.merge {
        remove_parts(&folder);
    }
    Ok(())
}

/// Removes a merged bake's parts folder (a failure only warns: the outputs are written).
fn remove_parts(folder: &Path) {
    if let Err(e) = std::fs::remove_dir_all(folder) {
        eprintln!("warning: {}: the parts are merged but could not be removed: {e}", folder.display());
    }
}

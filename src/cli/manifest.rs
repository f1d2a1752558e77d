//! The batch manifest: a JSON list of render jobs, each turned into the arguments of
//! `kelvin render` (so a job means exactly what the command line means, and is checked by the
//! same parser). `kelvin batch` runs the jobs; `kelvin batch --plan` prints them for a driver
//! that spreads them over machines (distributed/ray/).
//!
//! ```json
//! { "jobs": [ { "name": "cornell", "scene": "cornell.glb", "output": "out/cornell.exr",
//!               "size": "256x256", "spp": 64, "camera": { "environment_at": [0, 1, 0] },
//!               "settings": { "color": "spectral", "light_sampler": "bvh", "seed": 7,
//!                             "integrator": "path", "max_depth": 8 } },
//!             { "scene": "walk.glb", "output": "out/walk_####.exr", "frames": "0..47", "fps": 24,
//!               "animation": "walk" } ] }
//! ```
//! Relative paths are relative to the manifest's folder. Unknown keys are errors. A job with
//! `bake` runs `kelvin bake` instead (`bake_jobs.rs`). A job with
//! `frames` is planned as one job per frame (`--frames K`, the output's '#' run numbered), so
//! that frames, like tiles, can be spread, skipped when finished and retried one by one.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use clap::Parser;
use serde::{Deserialize, Serialize};

use super::frames::{FrameRange, frame_path};
use super::render::RenderArgs;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    /// The manifest format's version (absent: 1).
    pub version: Option<u32>,
    pub jobs: Vec<serde_json::Value>,
    /// The schema the file names for editors (`"$schema"`), not read.
    #[serde(rename = "$schema")]
    #[allow(dead_code)]
    pub schema: Option<String>,
}

/// The manifest version this kelvin reads.
pub const VERSION: u32 = 1;

/// One job as written in the manifest. Settings default as `kelvin render`'s flags do.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct JobSpec {
    /// For messages; the output's file name when absent (`plan_job` reads it from the JSON, so
    /// that it names even a job that does not parse).
    #[allow(dead_code)]
    name: Option<String>,
    /// glTF scene; the embedded default scene when absent.
    scene: Option<PathBuf>,
    /// .exr (with a .png preview) or .png.
    output: PathBuf,
    /// WIDTHxHEIGHT.
    size: Option<String>,
    spp: Option<u32>,
    #[serde(default)]
    camera: CameraSpec,
    /// Frames of the scene's animation, as `--frames` takes them ("0..47", "1-100x2", "1,5,10-20").
    #[allow(dead_code)] // read by `plan_frames` from the JSON
    frames: Option<String>,
    /// Frames per task: consecutive frames of `frames` rendered by one process, each an image of
    /// its own, bit for bit as when rendered alone (default 1).
    #[allow(dead_code)] // read by `plan_frames` from the JSON
    chunk: Option<u32>,
    /// Frames per second (default 24).
    fps: Option<f64>,
    /// The animation to play, by name or index (default the first).
    animation: Option<String>,
    /// `kelvin render` flags by name (`max_depth` is `--max-depth`; see `settings.rs`).
    #[serde(default)]
    settings: serde_json::Map<String, serde_json::Value>,
}

/// The scene's camera (the first one, or one framing the scene), or an environment camera.
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct CameraSpec {
    environment_at: Option<[f32; 3]>,
}

/// Flags a render job's settings may not set: the job's own keys (`frames`, `output`), the
/// driver's tiling (`crop`) and the machine's (`threads`, `report`, `log`: a task's log is the batch's).
pub(super) const RESERVED: [&str; 8] = ["output", "crop", "frames", "fps", "animation", "threads", "report", "log"];

/// A job ready to run, or why it cannot.
#[derive(Serialize)]
pub struct PlannedJob {
    /// The job's place in the manifest (the frames of one job share it).
    pub index: usize,
    /// The frame this job renders (the first, for a chunk), for a job with `frames`.
    pub frame: Option<i32>,
    /// Every frame it renders (more than one for a chunk); empty without `frames`.
    pub frames: Vec<i32>,
    pub name: String,
    /// Resolved output path (empty when the job did not parse).
    pub output: PathBuf,
    pub width: u32,
    pub height: u32,
    /// The `kelvin` command the job runs: "render" or "bake".
    pub command: &'static str,
    /// `kelvin render` (or `kelvin bake`) arguments, the output (`-o`) excepted.
    pub args: Vec<String>,
    /// A bake: the parts it is split into (`--part K/N`, then `--merge`), and the folder the
    /// merge reads them from.
    pub parts: u32,
    pub parts_dir: Option<PathBuf>,
    /// The output is finished: it exists, reads back, and (an EXR) records this job's scene,
    /// settings and frame (images are written under a temporary name, flushed and renamed).
    pub done: bool,
    /// Why an existing output is not this job's (it is rendered again).
    pub stale: Option<String>,
    /// Why the job cannot be split into tiles (ReSTIR's reuse): a driver renders it whole.
    pub untileable: Option<String>,
    /// Every file the job reads by name (scene, environment map) and its `sha256:` digest when planned:
    /// a driver checks that each machine holds the same before running the job there.
    pub inputs: BTreeMap<PathBuf, String>,
    /// The PNG preview's exposure in stops (None: automatic): what `kelvin merge` needs to write the
    /// preview `kelvin render` would.
    pub exposure: Option<f32>,
    pub error: Option<String>,
    /// Frames of a chunk whose files are finished. A farm task's entry (`kelvin batch --frames`)
    /// leaves them out of `frames`; a chunk of the manifest renders them again with the others.
    #[serde(skip)]
    pub finished: Vec<i32>,
}

impl PlannedJob {
    /// The job's `RenderArgs`, writing to `output`.
    pub fn render_args(&self, output: &Path) -> Result<RenderArgs, String> {
        parse_render_args(&self.args, output)
    }

    /// The images (or bake output) the job writes: a chunk's `output` is its job's pattern, and it
    /// writes one image per frame.
    pub fn outputs(&self) -> Vec<PathBuf> {
        match self.frames.as_slice() {
            [_, _, ..] => self.frames.iter().filter_map(|&k| frame_path(&self.output, k).ok()).collect(),
            _ => vec![self.output.clone()],
        }
    }
}

/// Most writers a "written by" error names.
const NAMED_WRITERS: usize = 3;

#[derive(Parser)]
#[command(name = "kelvin render")]
struct RenderCommand {
    #[command(flatten)]
    args: RenderArgs,
}

fn parse_render_args(args: &[String], output: &Path) -> Result<RenderArgs, String> {
    let argv = ["kelvin-render".to_owned()].into_iter().chain(args.iter().cloned());
    let argv = argv.chain(["-o".to_owned(), output.display().to_string()]);
    let parsed = RenderCommand::try_parse_from(argv).map_err(|e| {
        // clap's first line says what was wrong; the usage lines after it are for a terminal.
        let text = e.to_string();
        text.lines().next().unwrap_or_default().trim_start_matches("error: ").to_owned()
    })?;
    Ok(parsed.args)
}

/// The part of a manifest a farm task runs (`kelvin batch --job NAME --frames LIST`), chosen by what
/// stays the same when the manifest gains jobs: the job's name and frame numbers.
#[derive(Default)]
pub struct Selection<'a> {
    /// The job's `name` (a job without one: its `output` as written).
    pub job: Option<&'a str>,
    /// Frames of that job, planned as one entry (one process) of the frames not finished yet.
    pub frames: Option<&'a FrameRange>,
    /// Keep finished frames in that entry (`--force`).
    pub redo_finished: bool,
}

/// Reads the manifest at `path`: an error if it is not a manifest at all, or `selection` (default:
/// every job) names no job or two; otherwise the jobs chosen, each with its own error if it has one.
pub fn plan_selected(path: &Path, selection: &Selection) -> Result<Vec<PlannedJob>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
    plan_text_selected(&text, path, selection)
}

/// [`plan_selected`] of a manifest's text, `path` naming it and its folder (the base of relative
/// paths).
pub fn plan_text_selected(text: &str, path: &Path, selection: &Selection) -> Result<Vec<PlannedJob>, String> {
    let what = path.display();
    let manifest: Manifest = serde_json::from_str(text).map_err(|e| format!("{what}: not a manifest: {e}"))?;
    if let Some(v) = manifest.version.filter(|v| *v != VERSION) {
        return Err(format!("{what}: manifest version {v}; this kelvin reads version {VERSION}"));
    }
    let chosen = chosen_job(&manifest.jobs, selection).map_err(|e| format!("{what}: {e}"))?;
    // Absolute paths in the arguments, so that they mean the same from any working directory.
    let base = std::path::absolute(path).map_err(|e| format!("{what}: {e}"))?;
    let base = base.parent().unwrap_or(Path::new("/"));
    let digests = Digests::default();
    let mut jobs: Vec<PlannedJob> = Vec::new();
    for (i, job) in manifest.jobs.into_iter().enumerate() {
        jobs.extend(match chosen {
            // The other jobs' outputs only, for the check below: not their scenes, inputs or files.
            Some(c) if c != i => plan_frames(i, job, base, &digests, Depth::Outputs),
            Some(_) if selection.frames.is_some() => plan_task_frames(i, job, base, &digests, selection),
            _ => plan_frames(i, job, base, &digests, Depth::Full),
        });
    }
    // Two jobs writing one output would overwrite each other (and the second would find the first's
    // file "done"): both are errors, named.
    let mut writers: std::collections::HashMap<PathBuf, Vec<usize>> = std::collections::HashMap::new();
    for (k, job) in jobs.iter().enumerate().filter(|(_, j)| j.error.is_none()) {
        for output in job.outputs() {
            writers.entry(output).or_default().push(k);
        }
    }
    for (output, same) in writers.iter().filter(|(_, w)| w.len() > 1) {
        let mut names: Vec<String> =
            same.iter().take(NAMED_WRITERS).map(|&k| format!("job {} ({})", jobs[k].index, jobs[k].name)).collect();
        if same.len() > NAMED_WRITERS {
            names.push(format!("{} more", same.len() - NAMED_WRITERS));
        }
        let what = format!("{}: written by {}", output.display(), names.join(" and "));
        for &k in same {
            jobs[k].error.get_or_insert_with(|| what.clone());
        }
    }
    if let Some(c) = chosen {
        jobs.retain(|j| j.index == c);
    }
    Ok(jobs)
}

/// The index of the job `selection` chooses (None: every job), or why there is none.
fn chosen_job(jobs: &[serde_json::Value], selection: &Selection) -> Result<Option<usize>, String> {
    let Some(name) = selection.job else {
        return match (selection.frames, jobs.len()) {
            (None, _) => Ok(None),
            (Some(_), 1) => Ok(Some(0)),
            (Some(_), n) => Err(format!("--frames needs --job NAME: the manifest has {n} jobs")),
        };
    };
    let named = |job: &serde_json::Value| match job.get("name") {
        Some(n) => n.as_str() == Some(name),
        None => job.get("output").and_then(|o| o.as_str()) == Some(name),
    };
    let found: Vec<usize> = jobs.iter().enumerate().filter(|(_, j)| named(j)).map(|(i, _)| i).collect();
    match found[..] {
        [i] => Ok(Some(i)),
        [] => {
            let names: Vec<&str> =
                jobs.iter().filter_map(|j| j.get("name").or(j.get("output"))?.as_str()).take(NAMED_JOBS).collect();
            let more = if jobs.len() > NAMED_JOBS { ", ..." } else { "" };
            Err(format!("--job {name}: no job is named so (the jobs: {}{more})", names.join(", ")))
        }
        [a, b, ..] => Err(format!("--job {name}: jobs {a} and {b} are both named so; give each a name of its own")),
    }
}

/// Most job names a "no job is named so" error lists.
const NAMED_JOBS: usize = 10;

/// The entry of a farm task: the job's frames among `selection`'s, less those finished (unless
/// `redo_finished`), as one entry rendered in one process; an error entry if there are none.
fn plan_task_frames(
    index: usize,
    job: serde_json::Value,
    base: &Path,
    digests: &Digests,
    selection: &Selection,
) -> Vec<PlannedJob> {
    let failed = |why: String| {
        let mut failed = plan_job(index, &[], job.clone(), base, digests, Depth::Outputs);
        failed.error = Some(format!("job {index} ({}): {why}", failed.name));
        vec![failed]
    };
    let Some(wanted) = selection.frames else { return plan_frames(index, job, base, digests, Depth::Full) };
    let Some(spec) = job.get("frames") else { return failed("--frames: the job has no frames".into()) };
    let Some(spec) = spec.as_str() else {
        return failed(format!("frames: {spec} is not a string like \"0..47\" or \"1-100x2\""));
    };
    let range = match spec.parse::<FrameRange>() {
        Ok(range) => range,
        Err(e) => return failed(format!("frames: {e}")),
    };
    // The job's frames in the list: a task's `<STARTFRAME>-<ENDFRAME>` also spans frames a stepped job
    // skips, and OpenCue's last `#FRAME_END#` of a job can pass its end (OpenCue issue 1129).
    let frames: Vec<i32> = wanted.iter().filter(|&f| range.contains(f)).collect();
    if frames.is_empty() {
        return failed(format!("--frames: none of its frames is among the job's frames {spec}"));
    }
    let planned = plan_job(index, &frames, job.clone(), base, digests, Depth::Full);
    if selection.redo_finished || planned.done || planned.error.is_some() || planned.finished.is_empty() {
        return vec![planned];
    }
    // A retried task renders only what it has not finished (each frame's file says which).
    let todo: Vec<i32> = frames.into_iter().filter(|f| !planned.finished.contains(f)).collect();
    let mut rest = plan_job(index, &todo, job, base, digests, Depth::Full);
    rest.finished = planned.finished;
    vec![rest]
}

/// A job, or one job per frame of its `frames` (per `chunk` frames, with a chunk), planned to `depth`.
fn plan_frames(index: usize, job: serde_json::Value, base: &Path, digests: &Digests, depth: Depth) -> Vec<PlannedJob> {
    let frames = match job.get("frames") {
        None => return vec![plan_job(index, &[], job, base, digests, depth)],
        Some(f) => f.as_str().ok_or_else(|| format!("frames: {f} is not a string like \"0..47\" or \"1-100x2\"")),
    };
    let chunk = match job.get("chunk") {
        None => Ok(1),
        Some(c) => c
            .as_u64()
            .filter(|c| (1..=MAX_CHUNK).contains(c))
            .ok_or_else(|| format!("chunk: {c} is not a whole number in 1..={MAX_CHUNK}")),
    };
    let range = frames.and_then(|f| f.parse::<FrameRange>().map_err(|e| format!("frames: {e}")));
    match range.and_then(|r| Ok((r, chunk?))) {
        Ok((range, chunk)) => {
            let frames: Vec<i32> = range.iter().collect();
            frames.chunks(chunk as usize).map(|c| plan_job(index, c, job.clone(), base, digests, depth)).collect()
        }
        Err(e) => {
            let mut failed = plan_job(index, &[], serde_json::Value::Null, base, digests, Depth::Outputs);
            failed.error = Some(format!("job {index}: {e}"));
            vec![failed]
        }
    }
}

/// Most frames in one chunk.
const MAX_CHUNK: u64 = 10_000;

/// How much of a job [`plan_job`] plans.
#[derive(Clone, Copy, PartialEq)]
enum Depth {
    /// Its name and outputs: all that the check for outputs written twice needs.
    Outputs,
    /// Everything: arguments, inputs and their digests, finished or not.
    Full,
}

/// Plans `job`, for `frames` of its animation (none: a still; one: that frame; more: a chunk,
/// whose output is the job's pattern of '#').
fn plan_job(
    index: usize,
    frames: &[i32],
    job: serde_json::Value,
    base: &Path,
    digests: &Digests,
    depth: Depth,
) -> PlannedJob {
    let name = job.get("name").and_then(|n| n.as_str()).map(str::to_owned);
    let pattern = job.get("output").and_then(|o| o.as_str()).map(|o| base.join(o));
    let frame = frames.first().copied();
    let output = match (frames, &pattern) {
        ([k], Some(p)) => frame_path(p, *k).ok(),
        _ => pattern.clone(),
    };
    let label = match frames {
        [] => None,
        [k] => Some(format!("frame {k}")),
        [a, .., b] => Some(format!("frames {a}-{b}")),
    };
    let mut planned = PlannedJob {
        index,
        frame,
        frames: frames.to_vec(),
        name: name
            .clone()
            .map_or_else(|| format!("job {index}"), |n| label.as_ref().map_or(n.clone(), |l| format!("{n} {l}"))),
        output: output.clone().unwrap_or_default(),
        width: 0,
        height: 0,
        command: "render",
        args: Vec::new(),
        parts: 1,
        parts_dir: None,
        done: false,
        stale: None,
        untileable: None,
        inputs: BTreeMap::new(),
        exposure: None,
        error: None,
        finished: Vec::new(),
    };
    if name.is_none()
        && let Some(file) = output.as_ref().and_then(|o| o.file_name())
    {
        // A chunk's output is its job's pattern: its frames tell the chunks apart.
        let file = file.to_string_lossy();
        planned.name = match (frames, &label) {
            ([_, _, ..], Some(l)) => format!("{file} {l}"),
            _ => file.into_owned(),
        };
    }
    if depth == Depth::Outputs {
        return planned;
    }
    if job.get("bake").is_some() {
        planned.command = "bake";
        match super::bake_jobs::resolve(&job, base, &planned.output) {
            Ok(bake) => {
                (planned.done, planned.stale) = bake.parsed.finished();
                planned.parts_dir = Some(bake.parsed.output().1);
                match digests.of(&bake.parsed.input_files()) {
                    Ok(inputs) => planned.inputs = inputs,
                    Err(e) => planned.error = Some(format!("job {index} ({}): {e}", planned.name)),
                }
                (planned.args, planned.parts) = (bake.args, bake.parts);
            }
            Err(e) => planned.error = Some(format!("job {index} ({}): {e}", planned.name)),
        }
        return planned;
    }
    match resolve(job, frames, base) {
        Ok((args, parsed)) => {
            let ext = planned.output.extension().map(|e| e.to_ascii_lowercase());
            if !matches!(ext.as_ref().and_then(|e| e.to_str()), Some("exr" | "png")) {
                planned.error = Some(format!(
                    "job {index} ({}): output {}: use .exr or .png",
                    planned.name,
                    planned.output.display()
                ));
                return planned;
            }
            (planned.done, planned.stale) = (true, None);
            let outputs: Vec<(PathBuf, Option<i32>)> = match (frames, &pattern) {
                ([_, _, ..], Some(p)) => {
                    frames.iter().filter_map(|&k| Some((frame_path(p, k).ok()?, Some(k)))).collect()
                }
                _ => vec![(planned.output.clone(), frame)],
            };
            // A chunk is finished when each of its frames is.
            for (output, k) in outputs {
                let (done, stale) = finished(&output, &parsed, k);
                planned.done &= done;
                planned.stale = planned.stale.or(stale);
                if let (true, Some(k), [_, _, ..]) = (done, k, frames) {
                    planned.finished.push(k);
                }
            }
            if frames.len() > 1 {
                planned.untileable =
                    Some(format!("a chunk of {} frames renders whole frames in one process", frames.len()));
            }
            (planned.width, planned.height) = parsed.size();
            planned.untileable = planned.untileable.or(parsed.tiling_refusal());
            (planned.args, planned.exposure) = (args, parsed.exposure());
            match digests.of(&parsed.input_files()) {
                Ok(inputs) => planned.inputs = inputs,
                Err(e) => planned.error = Some(format!("job {index} ({}): {e}", planned.name)),
            }
        }
        Err(e) => planned.error = Some(format!("job {index} ({}): {e}", planned.name)),
    }
    planned
}

/// The `sha256:` digests of the files the plan's jobs read, each file hashed once (a job of many
/// frames names its scene in every entry).
#[derive(Default)]
struct Digests(std::cell::RefCell<std::collections::HashMap<PathBuf, String>>);

impl Digests {
    /// Each of `files` with its digest.
    fn of(&self, files: &[PathBuf]) -> Result<BTreeMap<PathBuf, String>, String> {
        let mut known = self.0.borrow_mut();
        let mut digest = |f: &Path| -> Result<String, String> {
            if let Some(d) = known.get(f) {
                return Ok(d.clone());
            }
            let d = kelvin::provenance::file_sha256(f).map_err(|e| format!("{}: {e}", f.display()))?;
            known.insert(f.to_path_buf(), d.clone());
            Ok(d)
        };
        files.iter().map(|f| Ok((f.to_path_buf(), digest(f)?))).collect()
    }
}

/// Whether `output` is a finished render of `args` (frame `frame`): it reads back and records
/// the same settings, frame and inputs (the scene, its buffers, images and IES profiles, the
/// environment map: each file it lists hashed again now). The program may differ: a rebuilt kelvin
/// renders the same image (tiles of different builds are refused by `kelvin merge`). Otherwise, for
/// an existing file, why not.
fn finished(output: &Path, args: &RenderArgs, frame: Option<i32>) -> (bool, Option<String>) {
    use kelvin::render::film_io::{read_exr_tile_and_provenance, read_png_provenance};
    if !output.exists() {
        return (false, None);
    }
    let png = output.extension().is_some_and(|e| e.eq_ignore_ascii_case("png"));
    let recorded = if png { read_png_provenance(output) } else { read_exr_tile_and_provenance(output).map(|(_, p)| p) };
    let recorded = match recorded {
        Ok(p) if p.0.is_empty() => return (false, Some("it records no provenance".into())),
        Ok(p) => p,
        Err(e) => return (false, Some(format!("does not read back: {e}"))),
    };
    let wanted = match args.inputs_now(&recorded) {
        Ok(inputs) => args.provenance(frame, None, inputs),
        Err(e) => return (false, Some(e)),
    };
    let ignore = ["program", "version", "animation", "animation_name"];
    if let Some((key, was, now)) = recorded.difference(&wanted, &ignore) {
        return (false, Some(format!("its {key} is {was}, the job's {now}")));
    }
    // The clip was resolved when rendering; the job names it by index or name.
    let clip = [recorded.0.get("animation"), recorded.0.get("animation_name")];
    if frame.is_some() && !clip.iter().flatten().any(|c| **c == args.animation()) {
        return (false, Some(format!("it shows another animation than {}", args.animation())));
    }
    (true, None)
}

/// The job's `kelvin render` arguments (without `-o`) and what its parser made of them; for
/// `frames` of a job with frames (one, or a chunk).
fn resolve(job: serde_json::Value, frames: &[i32], base: &Path) -> Result<(Vec<String>, RenderArgs), String> {
    let spec: JobSpec = serde_json::from_value(job).map_err(|e| e.to_string())?;
    let output = match frames {
        [k] => frame_path(&base.join(&spec.output), *k)?,
        _ => base.join(&spec.output),
    };
    let mut args = Vec::new();
    if !frames.is_empty() {
        let list: Vec<String> = frames.iter().map(i32::to_string).collect();
        args.extend(["--frames".to_owned(), list.join(",")]);
        if let Some(fps) = spec.fps {
            args.extend(["--fps".to_owned(), fps.to_string()]);
        }
        if let Some(a) = &spec.animation {
            args.extend(["--animation".to_owned(), a.clone()]);
        }
    } else if spec.fps.is_some() || spec.animation.is_some() {
        return Err("fps and animation need frames".into());
    }
    let mut push = |flag: &str, value: String| args.extend([flag.to_owned(), value]);
    let size = spec.size.unwrap_or_else(|| "512x512".into());
    push("--size", size);
    if let Some(spp) = spec.spp {
        push("--spp", spp.to_string());
    }
    if let Some([x, y, z]) = spec.camera.environment_at {
        push("--environment-at", format!("{x},{y},{z}"));
    }
    let mut settings = spec.settings;
    // `mis: false` is `--no-mis`, the flag's negation.
    if let Some(mis) = settings.remove("mis") {
        match mis.as_bool() {
            Some(false) => args.push("--no-mis".into()),
            Some(true) => {}
            None => return Err(format!("settings.mis: {mis} is not true or false")),
        }
    }
    args.extend(super::settings::flags(&settings, &RESERVED, base)?);
    if let Some(scene) = &spec.scene {
        let scene = base.join(scene);
        if !scene.is_file() {
            return Err(format!("scene {}: no such file", scene.display()));
        }
        args.push(scene.display().to_string());
    }
    let parsed = parse_render_args(&args, &output)?;
    Ok((args, parsed))
}

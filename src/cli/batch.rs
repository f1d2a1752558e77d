//! `kelvin batch MANIFEST [--plan] [--force] [--threads T] [--task N | --job NAME [--frames LIST]]
//! [--log FILE]`: renders (and bakes) a manifest's jobs one after another with a progress bar and a
//! summary. A job whose output exists is finished (images are written under a temporary name and
//! renamed, the .exr after its .png preview) and is skipped, so a rerun resumes; a job that fails
//! says why and the others still run. `--job` and `--frames` select a farm task's work by the job's
//! name and frame numbers, which stay the same when the manifest gains jobs (`--task N` shifts).

use std::path::PathBuf;

use super::CliError;
use super::exit::{self, Exit};
use super::frames::{FrameRange, task_frames};
use super::manifest::{PlannedJob, Selection, plan_selected};
use super::task_log::TaskLog;

/// The text `kelvin batch --help` ends with: a farm task's command line.
pub const FARM_HELP: &str = "A render farm's task names its job and frames: \
kelvin batch jobs.json --job walk --frames <STARTFRAME>-<ENDFRAME> --log logs/walk_<STARTFRAME>.log (Deadline), \
--frames #FRAMESPEC# (OpenCue). Exit codes: 2 bad input or settings (do not retry); 3 environment or I/O and 130 \
interrupted (retry, on another machine); see kelvin --help.";

#[derive(clap::Args)]
pub struct BatchArgs {
    /// The manifest: JSON, `{"jobs": [{"scene", "output", "size", "spp", "camera", "settings"}, ...]}`.
    #[arg(required_unless_present = "schema")]
    manifest: Option<PathBuf>,
    /// Print the manifest's JSON Schema (generated from the commands' definitions) and exit.
    #[arg(long)]
    schema: bool,
    /// Print the jobs as JSON (resolved `kelvin render` arguments, size, finished or not, errors)
    /// instead of rendering them: what a distributed driver reads.
    #[arg(long)]
    plan: bool,
    /// Render finished jobs (and, with --frames, finished frames) again.
    #[arg(long)]
    force: bool,
    /// Run only entry N (from 0) of the plan (`--plan` lists them; a job's frames are entries of
    /// their own). N shifts when jobs are added before it: a farm's task is better named by --job.
    #[arg(long, value_name = "N", conflicts_with = "plan")]
    task: Option<usize>,
    /// Run only the job of this name (its `name` in the manifest; a job without one by its `output`
    /// as written there): a farm task names its job, and still finds it when the manifest gains jobs.
    #[arg(long, value_name = "NAME", conflicts_with = "task")]
    job: Option<String>,
    /// Run only the job's frames among these (--job, or the manifest's only job), in one process,
    /// each frame the image it is alone; frames already finished are skipped, others of the list
    /// named and left out, none at all an error. The frame list a farm hands its task: Deadline's
    /// `<STARTFRAME>-<ENDFRAME>`, OpenCue's `#FRAMESPEC#` or `#FRAME_START#-#FRAME_END#` (a list as
    /// `render --frames` takes it, but no `A-B:S`: OpenCue's interleave, Open Job Description's step).
    #[arg(long, value_name = "FRAMES", allow_hyphen_values = true, conflicts_with = "task", value_parser = task_frames)]
    frames: Option<FrameRange>,
    /// Append each job's start, progress (`progress N%` lines, every 5% and at least every 30 s) and
    /// outcome, and the summary, to this file (its folder created), a line at a time with the UTC
    /// time, for a farm's monitor to tail. The same lines go to stderr when it is not a terminal.
    #[arg(long, value_name = "FILE")]
    log: Option<PathBuf>,
    /// Worker threads (default: all cores).
    #[arg(long, value_parser = super::values::threads())]
    threads: Option<usize>,
}

enum Outcome {
    Rendered(f64),
    Skipped,
    /// Why, and what kind of failure it was (the exit code it gives).
    Failed(String, Exit),
}

pub fn run(args: BatchArgs) -> Result<(), CliError> {
    if args.schema {
        println!("{}", serde_json::to_string_pretty(&super::settings::manifest_schema())?);
        return Ok(());
    }
    let Some(manifest) = &args.manifest else { return Err("no manifest given".into()) };
    let selection = Selection { job: args.job.as_deref(), frames: args.frames.as_ref(), redo_finished: args.force };
    let mut jobs = plan_selected(manifest, &selection)?;
    if let Some(n) = args.task {
        if n >= jobs.len() {
            return Err(format!("--task {n}: the plan has {} entries (0..{})", jobs.len(), jobs.len()).into());
        }
        jobs = vec![jobs.swap_remove(n)];
    }
    if args.plan {
        println!("{}", serde_json::to_string_pretty(&serde_json::json!({ "jobs": jobs }))?);
        return Ok(());
    }
    let log = TaskLog::open(args.log.as_deref())?;
    if let Some(t) = args.threads {
        rayon::ThreadPoolBuilder::new().num_threads(t).build_global()?;
    }
    let n = jobs.len();
    log.line(&format!(
        "kelvin batch {}: {n} entries, host {}, pid {}",
        manifest.display(),
        kelvin::render::partial::this_host(),
        std::process::id()
    ));
    for job in &jobs {
        remove_stale_temporaries(&job.output, &log);
    }
    let mut outcomes = Vec::with_capacity(n);
    for (k, job) in jobs.iter().enumerate() {
        if let (Some(why), false) = (&job.stale, args.force) {
            log.note(&format!(
                "{}: {} exists but is not this job's output ({why}); rendering it again",
                job.name,
                job.output.display()
            ));
        }
        if let Some(wanted) = &args.frames {
            let others: Vec<String> = wanted
                .iter()
                .filter(|f| !job.frames.contains(f) && !job.finished.contains(f))
                .map(|f| f.to_string())
                .collect();
            if let (Some(first), None) = (others.first(), &job.error) {
                let last = others.last().unwrap_or(first);
                let which = if others.len() > 1 {
                    format!("{} frames, {first} to {last},", others.len())
                } else {
                    format!("frame {first}")
                };
                log.note(&format!("[{}/{n}] {}: --frames: {which} not the job's, left out", k + 1, job.name));
            }
        }
        // A farm task's frames that a killed attempt of it finished (a manifest chunk renders its own again).
        let kept: Vec<String> = job.finished.iter().filter(|f| !job.frames.contains(f)).map(i32::to_string).collect();
        if !kept.is_empty() {
            log.line(&format!("[{}/{n}] {}: frames {} are finished already", k + 1, job.name, kept.join(",")));
        }
        let mut progress = log.job(k, n, &job.name);
        let outcome = run_job(job, args.force, |f| progress.set(f));
        progress.finish();
        let label = format!("[{}/{n}] {}", k + 1, job.name);
        log.line(&match &outcome {
            Outcome::Rendered(s) => format!("{label}: rendered in {s:.2} s: {}", job.output.display()),
            Outcome::Skipped => format!("{label}: skipped, {} is finished", job.output.display()),
            Outcome::Failed(e, code) => format!("{label}: FAILED (exit code {}): {e}", *code as u8),
        });
        outcomes.push(outcome);
    }
    let (mut rendered, mut skipped, mut failed) = (0, 0, 0);
    println!("{:<9} {:<24} {:>9}  output / cause", "status", "job", "seconds");
    for (job, outcome) in jobs.iter().zip(&outcomes) {
        let out = job.output.display();
        match outcome {
            Outcome::Rendered(s) => {
                rendered += 1;
                println!("{:<9} {:<24} {s:>9.2}  {out}", "rendered", job.name);
            }
            Outcome::Skipped => {
                skipped += 1;
                println!("{:<9} {:<24} {:>9}  {out} (exists; --force renders it again)", "skipped", job.name, "-");
            }
            Outcome::Failed(e, _) => {
                failed += 1;
                println!("{:<9} {:<24} {:>9}  {e}", "FAILED", job.name, "-");
            }
        }
    }
    let summary = format!("{n} jobs: {rendered} rendered, {skipped} skipped, {failed} failed");
    println!("{summary}");
    log.line(&summary);
    if failed > 0 {
        // One kind of failure (`--task`: one job) gives its own code, so a farm can tell; mixed ones 1.
        let mut kinds = outcomes.iter().filter_map(|o| if let Outcome::Failed(_, k) = o { Some(*k) } else { None });
        let first = kinds.next().unwrap_or(Exit::Failed);
        let exit = if kinds.all(|k| k == first) { first } else { Exit::Failed };
        return Err(Box::new(exit::Coded { exit, message: format!("{failed} of {n} jobs failed") }));
    }
    Ok(())
}

fn run_job(job: &PlannedJob, force: bool, progress: impl FnMut(f32) + Send) -> Outcome {
    if let Some(e) = &job.error {
        return Outcome::Failed(e.clone(), Exit::Input);
    }
    if job.done && !force {
        return Outcome::Skipped;
    }
    if job.command == "bake" {
        let start = std::time::Instant::now();
        return match bake(job) {
            Ok(()) => Outcome::Rendered(start.elapsed().as_secs_f64()),
            Err(e) => Outcome::Failed(format!("job {} ({}): {e}", job.index, job.name), exit::classify(&*e)),
        };
    }
    let result = job.render_args(&job.output).map_err(CliError::from).and_then(|render| {
        if let Some(dir) = job.output.parent() {
            std::fs::create_dir_all(dir).map_err(exit::io(dir.display()))?;
        }
        super::render::render_to_files(&render, progress)
    });
    match result {
        Ok(frames) => Outcome::Rendered(frames.iter().map(|r| r.stats.seconds).sum()),
        Err(e) => Outcome::Failed(format!("job {} ({}): {e}", job.index, job.name), exit::classify(&*e)),
    }
}

/// Runs a bake job: whole, or its parts one after another and then their merge (as a farm would
/// spread them).
fn bake(job: &PlannedJob) -> Result<(), CliError> {
    let output = ["-o".to_owned(), job.output.display().to_string()];
    let run = |extra: &[String]| {
        let argv: Vec<String> = job.args.iter().chain(extra).chain(&output).cloned().collect();
        let args = super::bake::parse(&argv)?;
        super::bake::run(args)
    };
    if job.parts <= 1 {
        return run(&[]);
    }
    for k in 1..=job.parts {
        run(&["--part".to_owned(), format!("{k}/{}", job.parts)])?;
    }
    run(&["--merge".to_owned()])
}

/// Removes what a killed writer left beside `output` (and inside it, for a bake's folder): the
/// temporaries of `film_io::write_file` that `partial::abandoned` judges left by a writer that stopped
/// (on this host a process that no longer runs; on any host one untouched for an hour), so that a
/// batch on storage shared with other machines never removes what another is writing.
fn remove_stale_temporaries(output: &std::path::Path, log: &TaskLog) {
    use kelvin::render::partial;
    let stem = output.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let beside = output.parent().map(|d| (d.to_path_buf(), format!(".{stem}")));
    let inside = output.is_dir().then(|| (output.to_path_buf(), ".".to_owned()));
    for (dir, prefix) in beside.into_iter().chain(inside) {
        let Ok(entries) = std::fs::read_dir(&dir) else { continue };
        for path in entries.filter_map(|e| e.ok()).map(|e| e.path()) {
            let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
            if !(name.starts_with(&prefix) && name.ends_with(partial::SUFFIX)) {
                continue;
            }
            if partial::abandoned(&path) && std::fs::remove_file(&path).is_ok() {
                log.note(&format!("removed {}, left by a writer that stopped", path.display()));
            }
        }
    }
}

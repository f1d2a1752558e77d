//! `kelvin batch MANIFEST [--plan] [--force] [--threads T]`: renders (and bakes) a manifest's jobs
//! one after another with a progress bar and a summary. A job whose output exists is finished (images are
//! written under a temporary name and renamed, the .exr after its .png preview) and is skipped, so
//! a rerun resumes; a job that fails says why and the others still run.

use std::path::PathBuf;

use super::CliError;
use super::exit::{self, Exit};
use super::manifest::{PlannedJob, plan};

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
    /// Render finished jobs again.
    #[arg(long)]
    force: bool,
    /// Run only entry N (from 0) of the plan (`--plan` lists them; a job's frames are entries of
    /// their own): what a render farm's task runner calls.
    #[arg(long, value_name = "N", conflicts_with = "plan")]
    task: Option<usize>,
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
    let mut jobs = plan(manifest)?;
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
    if let Some(t) = args.threads {
        rayon::ThreadPoolBuilder::new().num_threads(t).build_global()?;
    }
    for job in &jobs {
        remove_stale_temporaries(&job.output);
    }
    let n = jobs.len();
    let mut outcomes = Vec::with_capacity(n);
    for (k, job) in jobs.iter().enumerate() {
        if let (Some(why), false) = (&job.stale, args.force) {
            eprintln!(
                "{}: {} exists but is not this job's output ({why}); rendering it again",
                job.name,
                job.output.display()
            );
        }
        let bar = super::render::progress_bar();
        bar.set_message(format!("[{}/{n}] {} ", k + 1, job.name));
        let outcome = run_job(job, args.force, |f| bar.set_position((f * 1000.0) as u64));
        bar.finish_and_clear();
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
    println!("{n} jobs: {rendered} rendered, {skipped} skipped, {failed} failed");
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

/// Removes what a killed writer left beside `output` (and inside it, for a bake's folder): files
/// `.<name>.<pid>.partial` (see `film_io::write_file`) of a process that no longer runs.
fn remove_stale_temporaries(output: &std::path::Path) {
    let stem = output.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let beside = output.parent().map(|d| (d.to_path_buf(), format!(".{stem}")));
    let inside = output.is_dir().then(|| (output.to_path_buf(), ".".to_owned()));
    for (dir, prefix) in beside.into_iter().chain(inside) {
        let Ok(entries) = std::fs::read_dir(&dir) else { continue };
        for path in entries.filter_map(|e| e.ok()).map(|e| e.path()) {
            let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
            let Some(rest) = name.strip_prefix(&prefix).and_then(|r| r.strip_suffix(".partial")) else { continue };
            let pid = rest.rsplit('.').next().and_then(|p| p.parse::<u32>().ok());
            let running = pid.is_some_and(|p| std::path::Path::new(&format!("/proc/{p}")).exists());
            if !running && std::fs::remove_file(&path).is_ok() {
                eprintln!("removed {}, left by a writer that stopped", path.display());
            }
        }
    }
}

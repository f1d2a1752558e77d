//! Subcommands of the `kelvin` program; each file parses its arguments and calls the library.
mod bake;
mod bake_jobs;
mod batch;
mod bench;
mod exit;
mod frames;
mod ies;
pub mod manifest; // pub for the manifest fuzz target, which includes this module
mod merge;
mod render;
mod report;
mod settings;
mod spectrum;
mod task_log;
mod values;

use clap::{Parser, Subcommand};

/// kelvin: a physically based light system (PBR's "Light Sources", on an ECS).
#[derive(Parser)]
#[command(name = "kelvin", version, about, after_help = exit::HELP)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Colorimetry and photometry of an emission spectrum.
    Spectrum(spectrum::SpectrumArgs),
    /// Header, flux, peak intensity and beam angles of an IES LM-63 photometric file.
    Ies(ies::IesArgs),
    /// Render a glTF scene (or the embedded default scene): path traced, or direct lighting.
    Render(render::RenderArgs),
    /// Render a manifest's jobs (JSON); finished outputs are skipped, so a rerun resumes.
    #[command(after_help = batch::FARM_HELP)]
    Batch(batch::BatchArgs),
    /// Join tiles rendered with `render --crop` into the full image, checking they cover it once.
    Merge(merge::MergeArgs),
    /// Reports: `report accuracy` prices each accuracy knob in render time.
    Report(report::ReportArgs),
    /// Benchmarks: `bench lights` (many-lights table and plots), `bench render` (the render suite).
    Bench(bench::BenchArgs),
    /// Baked light for game engines: `bake lightmaps` writes a lightmap per mesh with TEXCOORD_1.
    Bake(bake::BakeArgs),
}

/// Errors the CLI reports: a message that names what failed.
pub type CliError = Box<dyn std::error::Error>;

/// The process's exit code for `error` ([`exit`]).
pub fn exit_code(error: &(dyn std::error::Error + 'static)) -> u8 {
    exit::classify(error) as u8
}

/// Runs the chosen subcommand.
pub fn run(cli: Cli) -> Result<(), CliError> {
    match cli.command {
        Command::Spectrum(args) => spectrum::run(args),
        Command::Ies(args) => ies::run(args),
        Command::Render(args) => render::run(args),
        Command::Merge(args) => merge::run(args),
        Command::Batch(args) => batch::run(args),
        Command::Report(args) => report::run(args),
        Command::Bench(args) => bench::run(args),
        Command::Bake(args) => bake::run(args),
    }
}

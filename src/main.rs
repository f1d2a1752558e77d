//! The `kelvin` command line.
mod cli;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let args = cli::Cli::parse();
    match cli::run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            // What failed, by code (see `kelvin --help`): a farm retries 3 and 130, not 2.
            ExitCode::from(cli::exit_code(&*e))
        }
    }
}

//! `eventtrack6d`: the EventTrack6D command-line tool.

mod bench;
mod convert;
mod eval;
mod inspect;
mod progress;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// Real-time 6D object pose tracking from an event camera and a depth camera.
#[derive(Debug, Parser)]
#[command(name = "eventtrack6d", version, about, long_about = None, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    Inspect(inspect::InspectArgs),
    Convert(convert::ConvertArgs),
    Eval(eval::EvalArgs),
    Bench(bench::BenchArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Inspect(args) => inspect::run(&args),
        Command::Convert(args) => convert::run(&args),
        Command::Eval(args) => eval::run(&args),
        Command::Bench(args) => bench::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

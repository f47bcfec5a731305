//! `eventtrack6d`: the EventTrack6D command-line tool.

mod args;
mod bench;
mod convert;
mod demo;
mod demo_sequence;
mod evaluate;
mod inspect;
mod paths;
mod progress;
mod reference;
mod run;
mod session;
mod track;

use clap::{CommandFactory, Parser, Subcommand};
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
    Demo(demo::DemoArgs),
    Run(run::RunArgs),
    Track(track::TrackArgs),
    Bench(bench::BenchArgs),
    Eval(evaluate::EvalArgs),
    Inspect(inspect::InspectArgs),
    Convert(convert::ConvertArgs),
    /// Print the command reference (docs/commands.md) as Markdown, from these commands' own help texts.
    #[command(hide = true)]
    Reference,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Inspect(args) => inspect::run(&args),
        Command::Convert(args) => convert::run(&args),
        Command::Eval(args) => evaluate::run(&args),
        Command::Bench(args) => bench::run(&args),
        Command::Run(args) => run::run(&args),
        Command::Demo(args) => demo::run(&args),
        Command::Track(args) => track::run(&args),
        Command::Reference => {
            reference::run(Cli::command());
            Ok(())
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

//! `eventtrack6d`: the EventTrack6D command-line tool.

mod args;
mod bench;
mod compare;
mod convert;
mod demo;
mod demo_sequence;
mod devices;
mod evaluate;
mod inspect;
mod paths;
mod progress;
mod record;
mod ros2_config;
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
    Compare(compare::CompareArgs),
    Eval(evaluate::EvalArgs),
    Inspect(inspect::InspectArgs),
    Convert(convert::ConvertArgs),
    Devices(devices::DevicesArgs),
    Record(record::RecordArgs),
    Ros2Config(ros2_config::Ros2ConfigArgs),
    /// Print the command reference (docs/commands.md) as Markdown, from these commands' own help texts.
    #[command(hide = true)]
    Reference,
}

/// What `eventtrack6d reference` (docs/commands.md) says besides the commands.
const REFERENCE_PAGE: cli_reference::Page<'static> = cli_reference::Page {
    defined_in: "tracker/app/src/bin/eventtrack6d/",
    regenerate: "ET6D_WRITE_DOCS=1 cargo test -p eventtrack6d --test reference",
    see_also: "The simulator's commands are in [commands-hil-sim.md](commands-hil-sim.md); the configuration files \
               and what `demo` and `run` print are described in [runtime.md](runtime.md).",
};

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Inspect(args) => inspect::run(&args),
        Command::Convert(args) => convert::run(&args),
        Command::Devices(args) => devices::run(&args),
        Command::Record(args) => record::run(&args),
        Command::Ros2Config(args) => ros2_config::run(&args),
        Command::Eval(args) => evaluate::run(&args),
        Command::Bench(args) => bench::run(&args),
        Command::Compare(args) => compare::run(&args),
        Command::Run(args) => run::run(&args),
        Command::Demo(args) => demo::run(&args),
        Command::Track(args) => track::run(&args),
        Command::Reference => {
            print!(
                "{}",
                cli_reference::markdown(Cli::command(), &REFERENCE_PAGE)
            );
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

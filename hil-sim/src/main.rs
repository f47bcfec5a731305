//! `hil-sim`: the hardware-in-the-loop simulator's command-line tool.

use anyhow::Context;
use clap::{Parser, Subcommand};
use drivers::event::Geometry;
use hil_sim::pattern::{RotatingBar, write_rotating_bar};
use std::fs::File;
use std::io::BufWriter;
use std::path::PathBuf;
use std::process::ExitCode;

/// Synthetic event + depth + ground-truth recordings for EventTrack6D, without hardware.
#[derive(Debug, Parser)]
#[command(name = "hil-sim", version, about, long_about = None, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Write a rotating-bar test pattern as an EVT 3.0 `.raw` stream carrying the rig's 120 Hz trigger
    /// pulses (every 4th one phase-coded for a 30 Hz depth exposure).
    Pattern {
        /// Output `.raw` file (overwritten).
        #[arg(long)]
        out: PathBuf,
        /// Length, seconds.
        #[arg(long, default_value_t = 2.0)]
        seconds: f64,
        /// Rotation rate, revolutions per second.
        #[arg(long, default_value_t = 1.0)]
        revolutions_per_s: f64,
        /// Noise events per pixel per second.
        #[arg(long, default_value_t = 0.1)]
        noise_hz: f64,
        /// Seed of the noise.
        #[arg(long, default_value_t = 1)]
        seed: u64,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Pattern {
            out,
            seconds,
            revolutions_per_s,
            noise_hz,
            seed,
        } => pattern(out, seconds, revolutions_per_s, noise_hz, seed),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn pattern(out: PathBuf, seconds: f64, rev: f64, noise: f64, seed: u64) -> anyhow::Result<()> {
    anyhow::ensure!(
        seconds.is_finite() && seconds > 0.0 && seconds <= 3600.0,
        "--seconds must be in (0, 3600]"
    );
    anyhow::ensure!(
        rev.is_finite() && rev > 0.0 && rev <= 100.0,
        "--revolutions-per-s must be in (0, 100]"
    );
    anyhow::ensure!(
        noise.is_finite() && (0.0..=1000.0).contains(&noise),
        "--noise-hz must be in [0, 1000]"
    );
    if let Some(parent) = out.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent)
            .with_context(|| format!("{}: cannot create directory", parent.display()))?;
    }
    let file = File::create(&out).with_context(|| format!("{}: cannot create", out.display()))?;
    let p = RotatingBar {
        geometry: Geometry::new(1280, 720),
        seconds,
        revolutions_per_s: rev,
        noise_rate_hz: noise,
        seed,
        ..RotatingBar::default()
    };
    let stats = write_rotating_bar(&p, BufWriter::new(file))
        .with_context(|| format!("{}", out.display()))?;
    eprintln!(
        "wrote {} CD events and {} trigger edges ({seconds} s) to {}",
        stats.cd_events,
        stats.trigger_edges,
        out.display()
    );
    Ok(())
}

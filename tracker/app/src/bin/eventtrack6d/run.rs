//! `eventtrack6d run --config FILE`: runs any runtime configuration (demo sequence, recording replay, live rig)
//! until its source ends or Ctrl-C, with live progress, and prints the summary (and accuracy when the recording
//! has ground truth).

use crate::{demo_sequence, session};
use anyhow::Result;
use clap::Args;
use drivers::recording::Recording;
use eventtrack6d::runtime::config::{self, SourceKind};
use std::path::PathBuf;

/// Run the real-time pipeline of a configuration file: source -> trigger timeline -> tracker thread -> sinks.
///
/// The source is a demo sequence, a recording replay or the live rig (`[source] kind`; the live rig reads the EVK4
/// over USB, with a recording's depth frames until the live D435i driver exists: docs/live-camera.md). Trigger edges become 120 Hz ticks; the tracker runs on its own
/// thread fed by a bounded queue (on overload the oldest event batch is dropped and counted; trigger edges and
/// depth frames are never dropped) and hands every tick's poses to each sink: pose CSV, zenoh / ROS 2, CAN. It runs
/// until the source ends or Ctrl-C, then prints the same summary as `demo`, followed, for a source with ground
/// truth, by the accuracy of each published object. Examples: config/default.toml (the demo) and
/// config/rig-evk4-d435i.toml (the rig). The pipeline, the summary and the configuration keys: docs/runtime.md.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// Configuration file (TOML). Relative paths in it are relative to its directory.
    #[arg(long, value_name = "FILE")]
    pub config: PathBuf,
    /// Where a `demo` source's generated sequence is cached (default: target/demo next to the executable, else
    /// $XDG_CACHE_HOME/eventtrack6d, else ~/.cache/eventtrack6d).
    #[arg(long, value_name = "DIR")]
    pub cache_dir: Option<PathBuf>,
    /// Do not score the poses against the recording's ground truth at the end.
    #[arg(long)]
    pub no_accuracy: bool,
    /// Also write a per-tick latency log (CSV: tick time, depth tick, waited / tick / sinks / latency / prepare
    /// microseconds) to FILE; overrides `[output] latency_log`.
    #[arg(long, value_name = "FILE")]
    pub latency_log: Option<PathBuf>,
    /// Stop after this many seconds of the source's stream (the camera's clock from its first event; a replay's
    /// recording time), as if Ctrl-C came then; overrides `[source] max_seconds`.
    #[arg(long, value_name = "S")]
    pub seconds: Option<f64>,
}

/// Runs the command.
pub fn run(args: &RunArgs) -> Result<()> {
    let mut config = config::load(&args.config)?;
    if let Ok(text) = std::fs::read_to_string(&args.config) {
        for note in config::unused_tables(&config, &text) {
            eprintln!("warning: {}: {note}", args.config.display());
        }
    }
    if let Some(s) = args.seconds {
        if !(s.is_finite() && s > 0.0 && s <= 1e6) {
            anyhow::bail!("--seconds {s}: must be a number of seconds in (0, 1000000]");
        }
        config.source.max_seconds = s;
    }
    if let Some(p) = &args.latency_log {
        config.output.latency_log = Some(session::from_working_dir(p)?);
    }
    if config.source.kind == SourceKind::Demo {
        let cache = args
            .cache_dir
            .clone()
            .unwrap_or_else(demo_sequence::default_cache_dir);
        demo_sequence::resolve(&mut config, &cache)?;
    }
    let recording = config.replay.as_ref().map(|r| r.recording.clone());
    let expected = recording
        .as_ref()
        .and_then(|r| Recording::open(r).ok())
        .and_then(|r| session::expected_ticks(&r));
    let summary = session::execute(&config, expected)?;
    println!("{summary}");
    let score = !args.no_accuracy && !summary.stopped;
    if let (Some(rec), Some(_), true) = (&recording, &summary.outputs.csv, score)
        && Recording::open(rec).is_ok_and(|r| r.ground_truth.is_some())
    {
        session::print_run_accuracy(rec, &summary, &config.tracker.method)?;
    }
    if let Some(revised) = session::revised_csv(&summary) {
        println!("revised poses:   {}", revised.display());
    }
    session::print_latency_log(&summary);
    Ok(())
}

//! `eventtrack6d demo`: the main job on its built-in default. Generates (or reuses) a short simulated sequence with
//! `hil-sim`, replays it in real time through the whole runtime with zenoh and CAN (candump log) publishing, shows
//! live progress, and prints poses published, rate, latency, drops and accuracy.

use crate::{demo_sequence, session};
use anyhow::{Context, Result, bail};
use clap::Args;
use drivers::recording::Recording;
use eventtrack6d::runtime::config::{self, Pace};
use std::path::{Path, PathBuf};

/// Run the built-in demo: no arguments, no hardware, no downloads.
///
/// A short sequence (by default a mug shaken at moderate speed for 2 s in front of simulated EVK4 + D435i cameras)
/// is generated once with hil-sim and cached; hil-sim must be next to this executable or on PATH (build it with
/// `cargo build --release -p hil-sim`). The sequence is replayed in real time through the whole runtime of
/// config/default.toml: trigger timeline, tracker thread, and every sink. Poses go to poses.csv, over zenoh
/// (ROS 2 PoseStamped on `eventtrack6d/<object>/pose`, status JSON on `eventtrack6d/status`, while it runs) and as
/// CAN frames to poses.candump.log. A progress line shows ticks, rate, latency and drops; Ctrl-C stops cleanly.
///
/// At the end it prints poses published, rate, latency per sink, drops, timeline and tracker counters, depth
/// arrival times, accuracy against the ground truth (ADD-S, ADD, AR) and the output files, and writes overlay.png
/// (reconstructed intensity with the model outline at six published poses). How to read each line: the README's
/// "What the demo prints", and docs/runtime.md. The options choose another sequence (each one is generated once
/// and cached) or change how it is replayed.
#[derive(Debug, Args)]
pub struct DemoArgs {
    /// Output directory for poses.csv, poses.candump.log and overlay.png, and poses.revised.csv when late depth
    /// frames revised published poses (default: <cache>/run). Created when missing; must not be a file.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Where the generated sequence is cached (default: target/demo next to the executable, else
    /// $XDG_CACHE_HOME/eventtrack6d, else ~/.cache/eventtrack6d).
    #[arg(long, value_name = "DIR")]
    pub cache_dir: Option<PathBuf>,
    /// Library object of the sequence (default from config/default.toml: mug).
    #[arg(long)]
    pub object: Option<String>,
    /// Motion profile: translation, rotation, shake, throw, hand-switch, depth (default: shake).
    #[arg(long)]
    pub motion: Option<String>,
    /// Speed: slow, moderate, fast (default: moderate).
    #[arg(long)]
    pub speed: Option<String>,
    /// Length of the sequence, seconds, 0.1 to 60 (default 2).
    #[arg(long)]
    pub seconds: Option<f64>,
    /// Generator seed (default 1); another seed is another sequence of the same kind.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Replay as fast as possible instead of in real time (the latency figures then describe a tracker that never
    /// idles).
    #[arg(long)]
    pub fast: bool,
    /// Do not publish over zenoh: no session is opened, for a machine where another process holds the ports or
    /// multicast is unwanted. The CSV and CAN sinks stay on.
    #[arg(long)]
    pub no_zenoh: bool,
    /// Also write a per-tick latency log (CSV: tick time, depth tick, waited / tick / sinks / latency / prepare
    /// microseconds) to FILE. Columns: docs/runtime.md.
    #[arg(long, value_name = "FILE")]
    pub latency_log: Option<PathBuf>,
    /// Deliver each depth frame this long after its exposure, 0 to 1000 ms, as a live depth camera's transport does
    /// (`[source] depth_latency_ms`; default 0: with its own tick). How the tracker uses late frames:
    /// docs/tracker.md.
    #[arg(long, value_name = "MS", value_parser = crate::args::parse_latency_ms)]
    pub depth_latency_ms: Option<f64>,
    /// Add up to this much to each depth frame's latency, 0 to 1000 ms, drawn per frame
    /// (`[source] depth_latency_jitter_ms`; default 0).
    #[arg(long, value_name = "MS", value_parser = crate::args::parse_latency_ms)]
    pub depth_latency_jitter_ms: Option<f64>,
    /// Tracker parameters in place of the configuration's `[tracker.parameters]`: a TOML file with their keys at
    /// top level, as for `track --params` (docs/tracker.md), e.g. config/tracker/ticks-only.toml
    /// (half the CPU on fast objects). Unknown keys are errors.
    #[arg(long, value_name = "TOML")]
    pub params: Option<PathBuf>,
}

/// Writes an image strip of six overlays (reconstructed intensity `I_t` with the model outline at the published
/// pose) spread over the run into `out/overlay.png` and returns its path.
fn write_overlay_strip(recording: &Path, poses_csv: &Path, out: &Path) -> Result<Option<PathBuf>> {
    let rec = Recording::open(recording)?;
    let text = std::fs::read_to_string(poses_csv)
        .with_context(|| format!("reading {}", poses_csv.display()))?;
    let poses = tracker::recording::parse_pose_csv(&text)
        .with_context(|| format!("{}", poses_csv.display()))?;
    if poses.is_empty() {
        return Ok(None);
    }
    let strip = eval::overlay_strip(&rec, &poses, 6, 320).map_err(anyhow::Error::msg)?;
    let path = out.join("overlay.png");
    strip
        .save(&path)
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(Some(path))
}

/// Runs the command.
pub fn run(args: &DemoArgs) -> Result<()> {
    let mut config = config::builtin_default()?;
    let d = &mut config.demo;
    if let Some(o) = &args.object {
        d.object = o.clone();
    }
    if let Some(m) = &args.motion {
        d.motion = m.clone();
    }
    if let Some(s) = &args.speed {
        d.speed = s.clone();
    }
    if let Some(s) = args.seconds {
        d.seconds = s;
    }
    if let Some(s) = args.seed {
        d.seed = s;
    }
    if args.fast {
        config.source.pace = Pace::Fast;
    }
    if args.no_zenoh {
        config.sinks.zenoh = false;
    }
    if let Some(ms) = args.depth_latency_ms {
        config.source.depth_latency_ms = ms;
    }
    if let Some(ms) = args.depth_latency_jitter_ms {
        config.source.depth_latency_jitter_ms = ms;
    }
    if let Some(p) = &args.latency_log {
        config.output.latency_log = Some(session::from_working_dir(p)?);
    }
    if let Some(p) = &args.params {
        config.tracker.parameters = crate::args::tracker_params(Some(p))?;
    }
    config::validate(&config, "eventtrack6d demo")?;
    let cache = args
        .cache_dir
        .clone()
        .unwrap_or_else(demo_sequence::default_cache_dir);
    let out = args.out.clone().unwrap_or_else(|| cache.join("run"));
    if out.exists() && !out.is_dir() {
        bail!("--out {}: is a file, not a directory", out.display());
    }
    config.output.dir = out.clone();
    let recording = demo_sequence::resolve(&mut config, &cache)?;
    let expected = Recording::open(&recording)
        .ok()
        .and_then(|r| session::expected_ticks(&r));
    eprintln!(
        "replaying {} {} through the runtime (tracker `{}`); Ctrl-C stops",
        recording.display(),
        if args.fast {
            "as fast as possible"
        } else {
            "in real time"
        },
        config.tracker.method
    );
    let summary = session::execute(&config, expected)?;
    println!("{summary}");
    if let Some(csv) = &summary.outputs.csv {
        if summary.stopped {
            println!(
                "accuracy:        not scored (stopped early; the poses cover only part of the sequence)"
            );
        } else {
            session::print_run_accuracy(&recording, &summary, &config.tracker.method)?;
        }
        println!("poses:           {}", csv.display());
        if let Some(revised) = session::revised_csv(&summary) {
            println!("revised poses:   {}", revised.display());
        }
        if let Some(p) = write_overlay_strip(&recording, csv, &out)? {
            println!("overlay:         {}", p.display());
        }
    }
    if let Some(log) = &summary.outputs.candump {
        println!(
            "CAN frames:      {} (decode with config/can/eventtrack6d.dbc)",
            log.display()
        );
    }
    session::print_latency_log(&summary);
    Ok(())
}

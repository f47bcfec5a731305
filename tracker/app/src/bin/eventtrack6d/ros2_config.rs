//! `eventtrack6d ros2-config`: the configuration that tracks a recording played over ROS 2.

use anyhow::{Context, Result};
use clap::Args;
use drivers::recording::Recording;
use eventtrack6d::runtime::ros2::{PlaybackEndpoints, playback_config};
use std::path::PathBuf;

/// Print the configuration that tracks a recording played over ROS 2 by `hil-sim ros2-play`.
///
/// `[source] kind = "ros2"` with the recording's calibration (camera.json) and trigger schedule, its objects at
/// their ground-truth poses at the first tick as `[[objects]]`, the pose CSV to --out, zenoh publishing on, and
/// the run ending 2 s after the last event packet. Then `eventtrack6d run --config FILE` waits for the topics and
/// `hil-sim ros2-play RECORDING` plays them (docs/zenoh-ros2.md, "Input"). For a real rig, copy it and give the
/// rig's calibration and the objects' placement instead.
#[derive(Debug, Args)]
pub struct Ros2ConfigArgs {
    /// The recording directory (camera.json, meta.json, models/, groundtruth).
    pub recording: PathBuf,
    /// zenoh endpoint the tracker's ROS 2 session connects to (repeatable).
    #[arg(long, default_value = "tcp/127.0.0.1:7447")]
    pub connect: Vec<String>,
    /// zenoh endpoint it listens on (repeatable; default none).
    #[arg(long)]
    pub listen: Vec<String>,
    /// Output directory written into the configuration (`[output] dir`).
    #[arg(long, default_value = "out-ros2")]
    pub out: PathBuf,
    /// Write the configuration here instead of printing it.
    #[arg(long, value_name = "FILE")]
    pub write: Option<PathBuf>,
}

/// Runs the command.
pub fn run(args: &Ros2ConfigArgs) -> Result<()> {
    let rec = Recording::open(&args.recording)?;
    let endpoints = PlaybackEndpoints {
        connect: args.connect.clone(),
        listen: args.listen.clone(),
    };
    let text = playback_config(&rec, &endpoints, &args.out)?;
    match &args.write {
        Some(path) => {
            std::fs::write(path, text).with_context(|| format!("writing {}", path.display()))?
        }
        None => print!("{text}"),
    }
    Ok(())
}

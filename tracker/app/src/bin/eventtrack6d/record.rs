//! `eventtrack6d record --config FILE --out DIR [--seconds T]`: captures a session on the live rig as a
//! recording directory.

use anyhow::Result;
use clap::Args;
use eventtrack6d::runtime::StopFlag;
use eventtrack6d::runtime::config;
use eventtrack6d::runtime::recorder::{RecordStats, record};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};

/// Record what the live rig sees as a recording directory, to replay or benchmark later with track, run and bench.
///
/// Opens the event camera of the configuration's `[live]` table (as `run` does: biases, event-rate controller,
/// trigger input), and writes DIR/events.raw with the camera's EVT 3.0 bytes exactly as they arrive, under a
/// header naming the camera, its serial number, firmware and biases; DIR/meta.json with the trigger schedule and
/// the session's counters. With `[live] depth_camera = "recording"` the depth recording's cameras (camera.json),
/// objects (models/), depth frames (depth/) and ground truth (groundtruth.csv, if any) are copied along. Prints a progress line every second and, at the
/// end, the drop counters: transfers dropped because the ring between USB and the disk was full leave a gap in
/// the file, which a replay's decoder skips and counts. Runs until --seconds of the camera's clock or Ctrl-C. A
/// camera that goes away is reopened. The set-up: docs/live-camera.md.
#[derive(Debug, Args)]
pub struct RecordArgs {
    /// Configuration file (TOML) with a `[live]` table, e.g. config/rig-evk4-d435i.toml.
    #[arg(long, value_name = "FILE")]
    pub config: PathBuf,
    /// Output recording directory (created; must not hold a recording already).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Stop after this many seconds of the camera's clock (default: until Ctrl-C).
    #[arg(long, value_name = "S")]
    pub seconds: Option<f64>,
}

static INTERRUPTED: AtomicBool = AtomicBool::new(false);

extern "C" fn on_interrupt(_: libc::c_int) {
    INTERRUPTED.store(true, Ordering::SeqCst);
}

fn line(s: &RecordStats) -> String {
    format!(
        "{:.1} s of stream, {:.1} MB, {} events, {} trigger edges, {} transfers dropped ({} bytes), {} gaps, {} outages",
        s.stream_s,
        s.bytes as f64 * 1e-6,
        s.events,
        s.trigger_edges,
        s.dropped_transfers,
        s.dropped_bytes,
        s.gaps,
        s.outages
    )
}

/// Runs the command.
pub fn run(args: &RecordArgs) -> Result<()> {
    if let Some(s) = args.seconds
        && !(s.is_finite() && s > 0.0 && s <= 1e6)
    {
        anyhow::bail!("--seconds {s}: must be a number of seconds in (0, 1000000]");
    }
    let config = config::load(&args.config)?;
    let stop = StopFlag::new();
    // SAFETY: the handler only stores to an atomic, which is async-signal-safe.
    unsafe {
        libc::signal(
            libc::SIGINT,
            on_interrupt as *const () as libc::sighandler_t,
        );
    }
    let watcher = {
        let stop = stop.clone();
        std::thread::spawn(move || {
            while !stop.is_set() {
                if INTERRUPTED.load(Ordering::SeqCst) {
                    eprintln!("\nstopping (Ctrl-C)");
                    stop.set();
                }
                std::thread::sleep(std::time::Duration::from_millis(20));
            }
        })
    };
    let result = record(&config, &args.out, args.seconds, &stop, |s| {
        eprint!("\rrecording: {}   ", line(s));
    });
    stop.set();
    let _ = watcher.join();
    let stats = result?;
    eprintln!();
    println!("recorded {} from {}", args.out.display(), stats.camera);
    println!("{}", line(&stats));
    let wall = stats.wall_s.max(1e-9);
    println!(
        "throughput: {:.1} MB/s, {:.2} Mev/s over {:.2} s of wall clock ({:.2} s of stream)",
        stats.bytes as f64 * 1e-6 / wall,
        stats.events as f64 * 1e-6 / wall,
        stats.wall_s,
        stats.stream_s
    );
    if stats.dropped_transfers > 0 {
        println!(
            "warning: {} transfers ({} bytes) were dropped: the disk or the machine could not keep up ([live] ring_mib)",
            stats.dropped_transfers, stats.dropped_bytes
        );
    }
    Ok(())
}

//! Running a configuration with live progress on the terminal, then scoring the published poses against the
//! recording's ground truth (shared by `run` and `demo`).

use anyhow::{Context, Result};
use drivers::recording::Recording;
use eval::{AucLimit, evaluate_object};
use eventtrack6d::runtime::{self, Config, Health, Hooks, StopFlag, Summary};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::path::Path;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tracker::recording::{
    PoseRecord, PoseTrack, apply_revisions, ground_truth_objects, parse_pose_csv, recording_ticks,
};

fn fmt_us(v: Option<f64>) -> String {
    v.map_or_else(|| "-".into(), |v| format!("{v:.0}us"))
}

/// Runs `config` to its end (or Ctrl-C) with a progress bar of `expected_ticks` on a terminal.
pub fn execute(config: &Config, expected_ticks: Option<u64>) -> Result<Summary> {
    let bar = ProgressBar::with_draw_target(expected_ticks, ProgressDrawTarget::stderr());
    let style = ProgressStyle::with_template("{spinner} [{bar:16}] {pos}/{len} {msg}")
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> ");
    bar.set_style(style);
    let shared = Arc::new(Mutex::new(bar.clone()));
    let progress = move |h: &Health| {
        let l = h.latency.summary();
        let rate = h
            .tick_rate_hz()
            .map_or_else(|| "-".into(), |r| format!("{r:.1} Hz"));
        let b = shared.lock().unwrap_or_else(|p| p.into_inner());
        b.set_position(h.ticks);
        b.set_message(format!(
            "{rate} | latency p50 {} p99 {} max {} | drops {}",
            fmt_us(l.p50_us),
            fmt_us(l.p99_us),
            fmt_us(l.max_us),
            h.queue.dropped_events
        ));
    };
    let hooks = Hooks {
        progress: Some(Box::new(progress)),
        progress_period: Duration::from_millis(100),
        before_start: None,
        stop: StopFlag::new(),
        ctrl_c: true,
    };
    let result = runtime::run(config, hooks);
    bar.finish_and_clear();
    Ok(result?)
}

/// The number of ticks a recording should produce at its trigger rate (for the progress bar).
pub fn expected_ticks(rec: &Recording) -> Option<u64> {
    let gt = rec.ground_truth.as_ref()?;
    let (first, last) = (gt.first()?.t_us, gt.iter().map(|p| p.t_us).max()?);
    Some(((last - first) as f64 * 1e-6 * rec.meta.trigger.tick_rate_hz).round() as u64)
}

/// ADD-S / ADD AUC and AR (percent, 120 Hz) of each object of `poses_csv` against `recording`'s ground truth. An
/// object the run published but the ground truth does not hold is named in a warning and not scored; objects of
/// the ground truth the run did not track are left out.
pub fn accuracy(
    recording: &Path,
    poses_csv: &Path,
    revised_csv: Option<&Path>,
) -> Result<Vec<(String, eval::Summary)>> {
    let rec = Recording::open(recording)?;
    let read = |path: &Path| -> Result<Vec<PoseRecord>> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("cannot read {}", path.display()))?;
        parse_pose_csv(&text).with_context(|| path.display().to_string())
    };
    let mut preds = read(poses_csv)?;
    if let Some(path) = revised_csv {
        apply_revisions(&mut preds, &read(path)?);
    }
    let ticks = recording_ticks(&rec)?;
    let in_ground_truth = ground_truth_objects(&rec)?;
    let mut published: Vec<String> = Vec::new();
    for p in &preds {
        if !published.contains(&p.object) {
            published.push(p.object.clone());
        }
    }
    let mut out = Vec::new();
    for object in published {
        if !in_ground_truth.contains(&object) {
            eprintln!(
                "warning: `{object}` has no ground truth in {} (objects there: {}): its accuracy is not scored",
                recording.display(),
                in_ground_truth.join(", ")
            );
            continue;
        }
        let track = PoseTrack::from_records(&preds, &object);
        let seq = evaluate_object(&rec, &ticks, &object, &track)?;
        out.push((object, seq.summary(false, AucLimit::Diameter)));
    }
    Ok(out)
}

/// The revised estimates' file a run wrote beside its pose CSV, if the tracker revised any.
pub fn revised_csv(summary: &Summary) -> Option<std::path::PathBuf> {
    let csv = summary.outputs.csv.as_ref()?;
    let path = eventtrack6d::publish::csv::CsvPoseSink::revised_path(csv);
    path.is_file().then_some(path)
}

/// Prints the accuracy of the published poses, and with the revised ones applied when the run revised any.
pub fn print_run_accuracy(recording: &Path, summary: &Summary, method: &str) -> Result<()> {
    let Some(csv) = &summary.outputs.csv else {
        return Ok(());
    };
    print_accuracy(&accuracy(recording, csv, None)?, method);
    if let Some(revised) = revised_csv(summary) {
        println!(
            "accuracy with the revised poses ({}; what the pose queries answer):",
            revised.display()
        );
        for (o, s) in accuracy(recording, csv, Some(&revised))? {
            println!(
                "  {o:<14} ADD-S {:6.2}  ADD {:6.2}  AR {:6.2}  ({} ticks)",
                s.add_s, s.add, s.ar, s.frames
            );
        }
    }
    Ok(())
}

/// Prints the accuracy table.
pub fn print_accuracy(rows: &[(String, eval::Summary)], method: &str) {
    println!("accuracy ({method}, every 120 Hz tick, AUC to 0.1 x diameter, percent):");
    for (o, s) in rows {
        println!(
            "  {o:<14} ADD-S {:6.2}  ADD {:6.2}  AR {:6.2}  ({} ticks)",
            s.add_s, s.add, s.ar, s.frames
        );
    }
}

/// `path` (from the command line) made absolute against the working directory, so that a configuration's
/// `output.dir` does not move it.
pub fn from_working_dir(path: &Path) -> Result<std::path::PathBuf> {
    Ok(std::env::current_dir()
        .context("reading the working directory")?
        .join(path))
}

/// Prints where the per-tick latency log went, when one was kept.
pub fn print_latency_log(summary: &Summary) {
    if let Some(log) = &summary.outputs.latency_log {
        println!(
            "latency log:     {} (one row per tick: {})",
            log.display(),
            runtime::LATENCY_LOG_HEADER
        );
    }
}

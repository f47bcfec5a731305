//! `eventtrack6d eval`: scores a tracker pose CSV against a recording's ground truth, per object, at 120 Hz (every
//! tick) and 30 Hz (depth-exposure ticks), like the paper's Tables 1 and 2.

use anyhow::{Context, Result, bail};
use clap::{Args, ValueEnum};
use drivers::recording::Recording;
use eval::{AucLimit, BopRow, Summary, evaluate_object, format_bop_csv};
use serde_json::{Map, json};
use std::path::PathBuf;
use tracker::recording::{
    PoseTrack, apply_revisions, ground_truth_objects, parse_pose_csv, recording_ticks,
};

/// AUC threshold convention.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum AucArg {
    /// Thresholds 0 to 0.1 x object diameter (the paper).
    Diameter,
    /// Thresholds 0 to 0.1 m (YCB-Video).
    Metres,
}

impl AucArg {
    /// The metric's threshold convention.
    pub fn limit(self) -> AucLimit {
        match self {
            AucArg::Diameter => AucLimit::Diameter,
            AucArg::Metres => AucLimit::Metres,
        }
    }
}

/// Score a tracker pose CSV against a recording's ground truth, like the paper's Tables 1 and 2.
///
/// Prints, per object, the AUC of ADD-S and ADD and the BOP average recall AR, in percent, at every 120 Hz tick
/// (the trigger timeline of events.raw) and at the depth-exposure ticks only (30 Hz). The prediction at a tick is
/// the latest row at or before it; ticks before an object's first row count as misses. The input is a pose CSV,
/// `t_us,object,x,y,z,qx,qy,qz,qw,quality,state` with that header line (bad rows are refused with the line and
/// field named). Ground truth that covers none of the ticks is an error. The metrics, the CSV and the JSON output:
/// docs/evaluation.md.
#[derive(Debug, Args)]
pub struct EvalArgs {
    /// Tracker output CSV.
    #[arg(long, value_name = "CSV")]
    pub pred: PathBuf,
    /// Revised estimates to apply first (a run's `poses.revised.csv`: ticks the tracker tracked again from late
    /// depth frames; the last row of a tick wins), to score what the pose queries answer rather than what was
    /// published.
    #[arg(long, value_name = "CSV")]
    pub revised: Option<PathBuf>,
    /// Recording directory with groundtruth.csv.
    #[arg(long, value_name = "RECORDING")]
    pub gt: PathBuf,
    /// Also write the scores as JSON to this file (it may not overwrite an input).
    #[arg(long, value_name = "OUT")]
    pub json: Option<PathBuf>,
    /// AUC threshold convention.
    #[arg(long, value_enum, default_value = "diameter")]
    pub auc: AucArg,
    /// Also export the predictions held at each tick as a BOP results CSV
    /// (`scene_id,im_id,obj_id,score,R,t,time`; scene 0, image = tick index, object id = 1-based rank of the name).
    #[arg(long, value_name = "CSV")]
    pub bop: Option<PathBuf>,
}

fn summary_json(s: &Summary) -> serde_json::Value {
    json!({"add_s": s.add_s, "add": s.add, "ar": s.ar, "frames": s.frames})
}

/// Runs the command.
pub fn run(args: &EvalArgs) -> Result<()> {
    let recording_files = crate::paths::recording_inputs(&args.gt);
    let mut inputs: Vec<crate::paths::NamedPath<'_>> = recording_files
        .iter()
        .map(|(name, path)| (*name, path.as_path()))
        .collect();
    inputs.push(("--pred", args.pred.as_path()));
    inputs.extend(args.revised.as_deref().map(|p| ("--revised", p)));
    let mut outputs = Vec::new();
    outputs.extend(args.json.as_deref().map(|p| ("--json", p)));
    outputs.extend(args.bop.as_deref().map(|p| ("--bop", p)));
    crate::paths::check_outputs(&inputs, &outputs)?;
    let text = std::fs::read_to_string(&args.pred)
        .with_context(|| format!("cannot read predictions {}", args.pred.display()))?;
    let mut preds = parse_pose_csv(&text).with_context(|| format!("{}", args.pred.display()))?;
    if let Some(path) = &args.revised {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("cannot read revised estimates {}", path.display()))?;
        let revised = parse_pose_csv(&text).with_context(|| format!("{}", path.display()))?;
        let applied = apply_revisions(&mut preds, &revised);
        println!(
            "{applied} of {} predictions revised from {} ({} rows)",
            preds.len(),
            path.display(),
            revised.len()
        );
    }
    let rec = Recording::open(&args.gt)?;
    let objects = ground_truth_objects(&rec)?;
    if objects.is_empty() {
        bail!(
            "{}: groundtruth.csv holds no poses, so there is nothing to score against",
            args.gt.display()
        );
    }
    for o in preds.iter().map(|p| &p.object) {
        if !objects.contains(o) {
            bail!(
                "{}: object `{o}` has no ground truth in {} (objects there: {})",
                args.pred.display(),
                args.gt.display(),
                objects.join(", ")
            );
        }
    }
    let ticks = recording_ticks(&rec)?;
    let limit = args.auc.limit();
    println!(
        "{} ticks ({} depth exposures); AUC thresholds to {}; values in percent",
        ticks.len(),
        ticks.iter().filter(|t| t.depth_frame.is_some()).count(),
        limit.describe()
    );
    println!(
        "{:<16} {:>8} {:>8} {:>8} | {:>8} {:>8} {:>8}",
        "object", "ADD-S", "ADD", "AR", "ADD-S30", "ADD30", "AR30"
    );
    let mut per_object = Map::new();
    let mut bop_rows = Vec::new();
    let (mut sum120, mut sum30) = ([0.0; 3], [0.0; 3]);
    for (obj_id, object) in objects.iter().enumerate() {
        let track = PoseTrack::from_records(&preds, object);
        if track.is_empty() {
            eprintln!("warning: no prediction for object `{object}`: every tick scores as missed");
        }
        let seq = evaluate_object(&rec, &ticks, object, &track)?;
        if seq.frames.len() < ticks.len() {
            eprintln!(
                "warning: `{object}` scored at {} of {} ticks: its ground truth covers only part of the recording",
                seq.frames.len(),
                ticks.len()
            );
        }
        let a = seq.summary(false, limit);
        let b = seq.summary(true, limit);
        println!(
            "{:<16} {:>8.2} {:>8.2} {:>8.2} | {:>8.2} {:>8.2} {:>8.2}",
            object, a.add_s, a.add, a.ar, b.add_s, b.add, b.ar
        );
        for (s, x) in [(&mut sum120, &a), (&mut sum30, &b)] {
            s[0] += x.add_s;
            s[1] += x.add;
            s[2] += x.ar;
        }
        per_object.insert(
            object.clone(),
            json!({"diameter_m": seq.diameter, "hz120": summary_json(&a), "hz30": summary_json(&b)}),
        );
        if args.bop.is_some() {
            for t in &ticks {
                if let Some(pose) = track.held_at(t.t_us) {
                    let quality = preds
                        .iter()
                        .rfind(|p| p.object == *object && p.t_us <= t.t_us)
                        .map_or(1.0, |p| p.quality);
                    bop_rows.push(BopRow {
                        scene_id: 0,
                        im_id: t.index,
                        obj_id: obj_id as u32 + 1,
                        score: quality,
                        pose,
                        time_s: -1.0,
                    });
                }
            }
        }
    }
    let n = objects.len().max(1) as f64;
    println!(
        "{:<16} {:>8.2} {:>8.2} {:>8.2} | {:>8.2} {:>8.2} {:>8.2}",
        "MEAN",
        sum120[0] / n,
        sum120[1] / n,
        sum120[2] / n,
        sum30[0] / n,
        sum30[1] / n,
        sum30[2] / n
    );
    if let Some(path) = &args.bop {
        std::fs::write(path, format_bop_csv(&bop_rows))
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    if let Some(path) = &args.json {
        let doc = json!({
            "recording": args.gt.display().to_string(),
            "predictions": args.pred.display().to_string(),
            "auc_threshold": limit.describe(),
            "objects": per_object,
            "mean": {"add_s": sum120[0] / n, "add": sum120[1] / n, "ar": sum120[2] / n},
            "mean_30hz": {"add_s": sum30[0] / n, "add": sum30[1] / n, "ar": sum30[2] / n},
        });
        std::fs::write(path, serde_json::to_string_pretty(&doc)? + "\n")
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    Ok(())
}

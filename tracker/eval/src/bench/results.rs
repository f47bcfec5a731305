//! What a benchmark run produces: per method, per sequence and object, the frame scores, the poses and the run
//! time, with the per-object and mean summaries the report prints.

use crate::recall::AucLimit;
use crate::sequence::{ObjectSequence, Summary, summarise};
use std::collections::BTreeMap;
use tracker::recording::PoseRecord;

/// One sequence of a suite.
#[derive(Debug, Clone, PartialEq)]
pub struct SuiteSequence {
    /// Sequence name (its directory name).
    pub name: String,
    /// The recording directory.
    pub dir: std::path::PathBuf,
    /// Motion profile (from `suite.json`, else the recording's generator parameters, else `-`).
    pub motion: String,
    /// Speed class (as `motion`).
    pub speed: String,
}

/// One method's results on one object of one sequence.
#[derive(Debug, Clone)]
pub struct SequenceResult {
    /// The sequence.
    pub sequence: SuiteSequence,
    /// Frame scores of the object.
    pub scores: ObjectSequence,
    /// The poses the method produced (tracker output rows).
    pub records: Vec<PoseRecord>,
    /// Seconds the method spent producing them (wall clock).
    pub seconds: f64,
}

/// All results of one method.
#[derive(Debug, Clone, Default)]
pub struct MethodResults {
    /// Method name.
    pub name: String,
    /// Per sequence (and object).
    pub sequences: Vec<SequenceResult>,
    /// The parameters it ran with ([`Method::parameters`]), recorded in `results.json`.
    pub parameters: Option<serde_json::Value>,
}

impl MethodResults {
    /// Poses per second of method run time over every sequence (infinite when it took no measurable time).
    pub fn update_hz(&self) -> f64 {
        let poses: usize = self.sequences.iter().map(|s| s.records.len()).sum();
        let secs: f64 = self.sequences.iter().map(|s| s.seconds).sum();
        if secs > 0.0 {
            poses as f64 / secs
        } else {
            f64::INFINITY
        }
    }

    /// Summary per object (frames of every sequence of that object pooled), 120 Hz or 30 Hz (`depth_only`).
    pub fn per_object(&self, depth_only: bool, limit: AucLimit) -> BTreeMap<String, Summary> {
        let mut by_object: BTreeMap<String, Vec<&SequenceResult>> = BTreeMap::new();
        for s in &self.sequences {
            by_object
                .entry(s.scores.object.clone())
                .or_default()
                .push(s);
        }
        by_object
            .into_iter()
            .map(|(object, seqs)| {
                let frames: Vec<_> = seqs
                    .iter()
                    .flat_map(|s| s.scores.frames.iter())
                    .filter(|f| !depth_only || f.depth_tick)
                    .collect();
                (object, summarise(&frames, seqs[0].scores.diameter, limit))
            })
            .collect()
    }

    /// Mean over objects of the per-object summaries (percent); `frames` is the total.
    pub fn mean(&self, depth_only: bool, limit: AucLimit) -> Summary {
        let per = self.per_object(depth_only, limit);
        let n = per.len().max(1) as f64;
        Summary {
            add_s: per.values().map(|s| s.add_s).sum::<f64>() / n,
            add: per.values().map(|s| s.add).sum::<f64>() / n,
            ar: per.values().map(|s| s.ar).sum::<f64>() / n,
            frames: per.values().map(|s| s.frames).sum(),
        }
    }
}

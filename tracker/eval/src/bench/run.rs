//! Running one method over one sequence: opening it, giving each object its first pose only, and scoring the
//! poses the method returns.

use super::method::{Method, MethodInput};
use super::results::{SequenceResult, SuiteSequence};
use crate::sequence::{EvalError, evaluate_object};
use drivers::recording::Recording;
use drivers::timeline::Tick;
use std::time::Instant;
use tracker::recording::{PoseTrack, ground_truth_objects, recording_ticks};

/// Runs `method` over one sequence: every object with ground truth, initialised from the ground truth at the
/// first tick only, then evaluated at every tick (an object whose ground truth covers no tick is an error). The
/// objects are handed to the method together ([`Method::track_together`]); each is charged an equal share of the
/// run time.
pub fn run_sequence(
    method: &mut dyn Method,
    sequence: &SuiteSequence,
    recording: &Recording,
    ticks: &[Tick],
) -> Result<Vec<SequenceResult>, EvalError> {
    let samples = recording.ground_truth.as_deref().unwrap_or(&[]);
    let mut objects = Vec::new();
    for object in ground_truth_objects(recording)? {
        let gt = PoseTrack::from_samples(samples, &object);
        let first = ticks
            .iter()
            .find_map(|t| gt.interpolated_at(t.t_us).map(|p| (t.t_us, p)))
            .ok_or_else(|| EvalError::Uncovered {
                object: object.clone(),
                ticks: ticks.len(),
            })?;
        objects.push((object, gt, first));
    }
    let inputs: Vec<MethodInput<'_>> = objects
        .iter()
        .map(|(object, gt, first)| MethodInput {
            recording,
            ticks,
            object,
            first_pose: *first,
            oracle: gt,
        })
        .collect();
    let start = Instant::now();
    let tracked = method.track_together(&inputs)?;
    let seconds = start.elapsed().as_secs_f64() / inputs.len().max(1) as f64;
    if tracked.len() != inputs.len() {
        return Err(EvalError::model(
            objects.first().map_or("", |o| o.0.as_str()),
            format!(
                "{} tracked {} of {} objects",
                method.name(),
                tracked.len(),
                inputs.len()
            ),
        ));
    }
    let mut out = Vec::new();
    for ((object, _, _), poses) in objects.iter().zip(tracked) {
        let track = PoseTrack::from_records(&poses, object);
        let scores = evaluate_object(recording, ticks, object, &track)?;
        out.push(SequenceResult {
            sequence: sequence.clone(),
            scores,
            records: poses,
            seconds,
        });
    }
    Ok(out)
}

/// Opens a sequence's recording and its ticks (shared by every method).
pub fn open_sequence(sequence: &SuiteSequence) -> Result<(Recording, Vec<Tick>), EvalError> {
    let rec = Recording::open(&sequence.dir)?;
    let ticks = recording_ticks(&rec)?;
    Ok((rec, ticks))
}

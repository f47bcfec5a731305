//! The interface every benchmarked pose-tracking method implements, and what it is given.

use crate::sequence::EvalError;
use drivers::recording::Recording;
use drivers::timeline::Tick;
use nalgebra::Isometry3;
use tracker::recording::{PoseRecord, PoseTrack};

/// What a method is given for one object in one sequence.
pub struct MethodInput<'a> {
    /// The recording (events, depth, cameras, models).
    pub recording: &'a Recording,
    /// The 120 Hz ticks at which a pose is expected, in time order.
    pub ticks: &'a [Tick],
    /// Object name.
    pub object: &'a str,
    /// The only initialisation: the ground-truth pose at the first evaluated tick (time microseconds, `T_cam_obj`).
    pub first_pose: (i64, Isometry3<f64>),
    /// Ground truth of the object, for oracle baselines only (`gt-noise`); real trackers must not read it.
    pub oracle: &'a PoseTrack,
}

/// A pose-tracking method under benchmark.
pub trait Method {
    /// Name in reports (the spec it was built from, e.g. `gt-noise:10:5`).
    fn name(&self) -> &str;
    /// Tracks `input.object` over the recording and returns its poses (typically one per tick).
    fn track(&mut self, input: &MethodInput<'_>) -> Result<Vec<PoseRecord>, EvalError>;
    /// Tracks the objects of `inputs`, all of one recording, and returns each one's poses in the same order. The
    /// default tracks them one at a time; a method that tracks several objects together (so that they can hide
    /// each other) overrides it.
    fn track_together(
        &mut self,
        inputs: &[MethodInput<'_>],
    ) -> Result<Vec<Vec<PoseRecord>>, EvalError> {
        inputs.iter().map(|input| self.track(input)).collect()
    }
    /// The parameters it runs with, as the report records them (`None`: its name says everything).
    fn parameters(&self) -> Option<serde_json::Value> {
        None
    }
}

//! The trivial tracker: every object keeps its initial pose. Used to test the runtime's plumbing and as the
//! `static` floor of the benchmark.

use super::{DepthHandling, PoseEstimate, PoseTracker, TrackingState};
use drivers::event::CdEvent;
use drivers::recording::DepthFrame;
use drivers::timeline::Tick;
use nalgebra::Isometry3;

/// Holds each object's initial pose forever, with quality 1 and state `tracking`.
#[derive(Debug, Clone)]
pub struct HoldPoseTracker {
    names: Vec<String>,
    poses: Vec<Isometry3<f64>>,
    last_tick_us: Option<i64>,
}

impl HoldPoseTracker {
    /// A tracker of `objects` (name, initial `T_cam_obj`).
    pub fn new(objects: Vec<(String, Isometry3<f64>)>) -> Self {
        let (names, poses) = objects.into_iter().unzip();
        Self {
            names,
            poses,
            last_tick_us: None,
        }
    }
}

impl PoseTracker for HoldPoseTracker {
    fn objects(&self) -> &[String] {
        &self.names
    }
    fn push_events(&mut self, _events: &[CdEvent]) {}
    fn push_depth(&mut self, _t_us: i64, _frame: &mut DepthFrame, _handling: DepthHandling) {}
    fn tick(&mut self, tick: &Tick, out: &mut Vec<PoseEstimate>) {
        self.last_tick_us = Some(tick.t_us);
        out.extend(
            self.poses
                .iter()
                .enumerate()
                .map(|(object, pose)| PoseEstimate {
                    object,
                    t_us: tick.t_us,
                    pose: *pose,
                    quality: 1.0,
                    state: TrackingState::Tracking,
                }),
        );
    }
    fn reseed(&mut self, object: usize, _t_us: i64, pose: Isometry3<f64>) -> Result<(), String> {
        if !is_finite(&pose) {
            return Err("the pose is not finite".into());
        }
        let held = self
            .poses
            .get_mut(object)
            .ok_or_else(|| format!("no object {object}"))?;
        *held = pose;
        Ok(())
    }
    fn pose_at(&self, object: usize, t_us: i64) -> Option<PoseEstimate> {
        self.last_tick_us?;
        self.poses.get(object).map(|pose| PoseEstimate {
            object,
            t_us,
            pose: *pose,
            quality: 1.0,
            state: TrackingState::Tracking,
        })
    }
}

/// Whether every number of `pose` is finite.
pub(crate) fn is_finite(pose: &Isometry3<f64>) -> bool {
    pose.translation.vector.iter().all(|v| v.is_finite())
        && pose.rotation.coords.iter().all(|v| v.is_finite())
}

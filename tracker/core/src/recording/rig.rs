//! The tracking rig of a recording or rig description (event camera, depth camera, extrinsics) and the ticks of
//! its trigger timeline.

use super::SetupError;
use crate::recon::DepthRig;
use crate::track::{TickClock, TrackingRig};
use drivers::event::{EventSink, TriggerEdge};
use drivers::recording::{CameraIntrinsics, CameraRig, Recording, RecordingError};
use drivers::timeline::{Tick, TickIter, TimelineConfig};
use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion};
use scene::geometry::PinholeCamera;

/// The pinhole camera of recorded intrinsics; `camera` names it in the error (`event camera`, `depth camera`).
pub fn camera_of(c: &CameraIntrinsics, camera: &'static str) -> Result<PinholeCamera, SetupError> {
    PinholeCamera::new(c.fx, c.fy, c.cx, c.cy, c.width, c.height).map_err(|e| SetupError::Camera {
        camera,
        reason: e.to_string(),
    })
}

/// `T_event_depth` of a rig: maps depth-camera points (metres) into the event camera's frame.
pub fn event_from_depth(rig: &CameraRig) -> Isometry3<f64> {
    let m = rig.t_event_depth;
    let r = Matrix3::new(
        m[0][0], m[0][1], m[0][2], m[1][0], m[1][1], m[1][2], m[2][0], m[2][1], m[2][2],
    );
    Isometry3::from_parts(
        Translation3::new(m[0][3], m[1][3], m[2][3]),
        UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r)),
    )
}

/// The tracking rig of a camera rig description (event camera, depth camera, extrinsics) triggered on `timeline`.
pub fn tracking_rig(rig: &CameraRig, timeline: &TimelineConfig) -> Result<TrackingRig, SetupError> {
    Ok(TrackingRig {
        event_camera: camera_of(&rig.event_camera, "event camera")?,
        depth: DepthRig {
            camera: camera_of(&rig.depth_camera, "depth camera")?,
            event_from_depth: event_from_depth(rig),
        },
        clock: TickClock::of(timeline),
    })
}

/// The tracking rig of a recording ([`tracking_rig`] of its rig and trigger schedule).
pub fn recording_rig(rec: &Recording) -> Result<TrackingRig, SetupError> {
    tracking_rig(&rec.rig, &rec.meta.trigger.timeline_config())
}

struct TriggerCollector(Vec<TriggerEdge>);

impl EventSink for TriggerCollector {
    fn cd(&mut self, _: drivers::event::CdEvent) {}
    fn cd_vector(&mut self, _: i64, _: u16, _: u16, _: u32, _: bool) {}
    fn trigger(&mut self, edge: TriggerEdge) {
        self.0.push(edge);
    }
}

/// The recording's 120 Hz ticks (trigger rising edges through [`drivers::timeline`]), in order.
pub fn recording_ticks(rec: &Recording) -> Result<Vec<Tick>, SetupError> {
    let mut reader = rec.events()?;
    let mut sink = TriggerCollector(Vec::new());
    reader.read_all(&mut sink).map_err(|e| RecordingError {
        path: rec.dir().join("events.raw"),
        problem: e.to_string(),
    })?;
    let ticks: Vec<Tick> =
        TickIter::new(rec.meta.trigger.timeline_config(), sink.0.into_iter()).collect();
    if ticks.is_empty() {
        return Err(SetupError::NoTicks(rec.dir().display().to_string()));
    }
    Ok(ticks)
}

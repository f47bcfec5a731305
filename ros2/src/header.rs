//! `builtin_interfaces/msg/Time` and `std_msgs/msg/Header`, the first fields of most messages.

use crate::CdrError;
use crate::wire::{CdrReader, CdrWriter};
use nalgebra::Isometry3;

/// A `builtin_interfaces/msg/Time`: seconds and nanoseconds since the ROS time epoch.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
pub struct RosTime {
    /// Whole seconds (may be negative).
    pub sec: i32,
    /// Nanoseconds within the second, `0..1_000_000_000`.
    pub nanosec: u32,
}

impl RosTime {
    /// Splits a time in nanoseconds into seconds and a non-negative nanosecond part (floor division, as ROS does).
    pub fn from_nanos(nanos: i64) -> Result<Self, CdrError> {
        let sec = nanos.div_euclid(1_000_000_000);
        let nanosec = nanos.rem_euclid(1_000_000_000);
        let sec = i32::try_from(sec).map_err(|_| CdrError::TimeOutOfRange {
            nanos: nanos.into(),
        })?;
        // rem_euclid of a positive modulus is in 0..1e9, which fits u32.
        Ok(Self {
            sec,
            nanosec: nanosec as u32,
        })
    }

    /// The time in nanoseconds.
    pub fn as_nanos(self) -> i64 {
        i64::from(self.sec) * 1_000_000_000 + i64::from(self.nanosec)
    }

    pub(crate) fn write(self, w: &mut CdrWriter<'_>) {
        w.i32(self.sec);
        w.u32(self.nanosec);
    }

    pub(crate) fn read(r: &mut CdrReader<'_>, field: &'static str) -> Result<Self, CdrError> {
        Ok(Self {
            sec: r.i32(field)?,
            nanosec: r.u32(field)?,
        })
    }
}

/// A `std_msgs/msg/Header`: when and in which frame.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Header {
    /// `stamp`.
    pub stamp: RosTime,
    /// `frame_id`: the coordinate frame the data is in.
    pub frame_id: String,
}

impl Header {
    /// A header at `stamp` in `frame_id`.
    pub fn new(stamp: RosTime, frame_id: &str) -> Self {
        Self {
            stamp,
            frame_id: frame_id.to_owned(),
        }
    }

    pub(crate) fn write(&self, w: &mut CdrWriter<'_>) {
        self.stamp.write(w);
        w.string(&self.frame_id);
    }

    pub(crate) fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self {
            stamp: RosTime::read(r, "header.stamp")?,
            frame_id: r.string("header.frame_id")?,
        })
    }
}

/// A `geometry_msgs/msg/Pose`: position (metres) and orientation (x, y, z, w).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Pose {
    /// `position` x, y, z.
    pub position: [f64; 3],
    /// `orientation` x, y, z, w.
    pub orientation_xyzw: [f64; 4],
}

impl Pose {
    /// The pose of an isometry (`T_frame_child`).
    pub fn from_isometry(pose: &Isometry3<f64>) -> Self {
        let (position, orientation_xyzw) = pose_fields(pose);
        Self {
            position,
            orientation_xyzw,
        }
    }

    /// Whether every number is finite.
    pub fn is_finite(&self) -> bool {
        self.position
            .iter()
            .chain(&self.orientation_xyzw)
            .all(|v| v.is_finite())
    }

    pub(crate) fn write(&self, w: &mut CdrWriter<'_>) {
        w.f64s(&self.position);
        w.f64s(&self.orientation_xyzw);
    }

    pub(crate) fn read(r: &mut CdrReader<'_>, field: &'static str) -> Result<Self, CdrError> {
        Ok(Self {
            position: r.f64s(field)?,
            orientation_xyzw: r.f64s(field)?,
        })
    }
}

/// Position and (x, y, z, w) orientation of an isometry, as they go on the wire.
pub fn pose_fields(pose: &Isometry3<f64>) -> ([f64; 3], [f64; 4]) {
    let t = &pose.translation.vector;
    let q = pose.rotation.quaternion();
    ([t.x, t.y, t.z], [q.i, q.j, q.k, q.w])
}

//! Where poses go: sinks that the runtime hands every tick's estimates to (zenoh / ROS 2, CAN, files).
//!
//! A sink never blocks the caller for long and never panics on a transport failure: failures are counted in
//! [`SinkCounters`] and reported, and the sink carries on (retrying where the transport allows).

pub mod can;
pub mod control;
pub mod csv;
/// The ROS 2 wire formats (the `eventtrack6d-ros2` crate), re-exported for the sinks' users.
pub use ::ros2;
mod shared;
pub mod zenoh;

pub use shared::SharedSink;

use drivers::timeline::Tick;
use std::time::Instant;
use tracker::track::PoseEstimate;

/// One tick's output as handed to sinks.
#[derive(Debug, Clone, Copy)]
pub struct TickPoses<'a> {
    /// The tick (index, time on the event camera's clock).
    pub tick: &'a Tick,
    /// One estimate per tracked object, in object order.
    pub estimates: &'a [PoseEstimate],
    /// Object names; `PoseEstimate::object` indexes this slice.
    pub objects: &'a [String],
    /// Wall-clock instant at which the tick's trigger edge was decoded (start of the latency measurement).
    pub decoded_at: Instant,
}

/// What a sink has done so far.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct SinkCounters {
    /// Poses handed to the transport successfully.
    pub published: u64,
    /// Poses not delivered because the transport failed (write error, bus-off, closed session).
    pub failed: u64,
    /// Poses dropped because the sink's own bounded queue was full.
    pub dropped: u64,
}

/// Why a sink could not publish.
#[derive(Debug, thiserror::Error)]
pub enum PublishError {
    /// The transport refused or failed (message names the sink and the cause).
    #[error("{sink}: {message}")]
    Transport {
        /// Sink name, e.g. `zenoh` or `can:vcan0`.
        sink: String,
        /// What went wrong.
        message: String,
    },
}

impl PublishError {
    /// `Ok` when no pose of a tick failed, else the first failure's message as a transport error of `sink`
    /// (the rest are counted in the sink's counters).
    pub fn from_first(sink: &str, first_error: Option<String>) -> Result<(), PublishError> {
        match first_error {
            None => Ok(()),
            Some(message) => Err(PublishError::Transport {
                sink: sink.to_string(),
                message,
            }),
        }
    }
}

/// A destination for poses.
pub trait PoseSink: Send {
    /// Short name for logs and the status topic (e.g. `zenoh`, `can:can0`, `candump:out.log`, `csv:poses.csv`).
    fn name(&self) -> &str;
    /// Publishes one tick's estimates. Must return promptly; a failure is counted and returned, never panics.
    fn publish(&mut self, poses: &TickPoses<'_>) -> Result<(), PublishError>;
    /// Counters since creation.
    fn counters(&self) -> SinkCounters;
    /// Flushes buffered output (files); called at shutdown.
    fn flush(&mut self) -> Result<(), PublishError> {
        Ok(())
    }
    /// Estimates of ticks already published whose pose the tracker has since revised: it tracked them again from
    /// a depth frame that arrived after them (quality and state are as published). A sink that keeps published
    /// poses to answer from (the zenoh pose queries) takes the revised ones; what was sent cannot be taken back,
    /// so by default nothing happens.
    fn revise(&mut self, revised: &[PoseEstimate]) {
        let _ = revised;
    }
}

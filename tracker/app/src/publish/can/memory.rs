//! In-memory CAN sink for tests: every frame is appended to a list shared through an `Arc`.

use super::layout::{CanFrame, EncodedPose, PoseEncoder, PoseFields};
use crate::publish::{PoseSink, PublishError, SinkCounters, TickPoses};
use std::sync::{Arc, Mutex, MutexGuard};

/// Handle to the frames a [`MemorySink`] has "sent" (cloneable, usable after the sink moved into the runtime).
#[derive(Debug, Clone, Default)]
pub struct MemoryFrames(Arc<Mutex<Vec<CanFrame>>>);

impl MemoryFrames {
    fn lock(&self) -> MutexGuard<'_, Vec<CanFrame>> {
        self.0.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// A copy of every frame so far, in transmission order.
    pub fn snapshot(&self) -> Vec<CanFrame> {
        self.lock().clone()
    }

    /// Number of frames so far.
    pub fn len(&self) -> usize {
        self.lock().len()
    }

    /// `true` when nothing was sent yet.
    pub fn is_empty(&self) -> bool {
        self.lock().is_empty()
    }
}

/// A [`PoseSink`] that keeps the encoded frames in memory.
pub struct MemorySink {
    name: String,
    encoder: PoseEncoder,
    frames: MemoryFrames,
    counters: SinkCounters,
    scratch: EncodedPose,
}

impl MemorySink {
    /// A sink encoding with `encoder`.
    pub fn new(encoder: PoseEncoder) -> Self {
        let mode = if encoder.fd { "fd" } else { "classic" };
        Self {
            name: format!("can-memory:{mode}"),
            encoder,
            frames: MemoryFrames::default(),
            counters: SinkCounters::default(),
            scratch: EncodedPose::default(),
        }
    }

    /// The shared frame list.
    pub fn frames(&self) -> MemoryFrames {
        self.frames.clone()
    }
}

impl PoseSink for MemorySink {
    fn name(&self) -> &str {
        &self.name
    }

    fn publish(&mut self, poses: &TickPoses<'_>) -> Result<(), PublishError> {
        let mut first_error = None;
        for est in poses.estimates {
            let fields = PoseFields::from_estimate(est, poses.tick.index);
            match self.encoder.encode_into(&fields, &mut self.scratch) {
                Ok(()) => {
                    self.frames.lock().extend_from_slice(self.scratch.frames());
                    self.counters.published += 1;
                }
                Err(e) => {
                    self.counters.failed += 1;
                    first_error.get_or_insert_with(|| format!("object {}: {e}", est.object));
                }
            }
        }
        PublishError::from_first(&self.name, first_error)
    }

    fn counters(&self) -> SinkCounters {
        self.counters
    }
}

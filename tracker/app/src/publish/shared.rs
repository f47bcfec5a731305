//! A pose sink shared between the tracker thread and another task.

use super::{PoseSink, PublishError, SinkCounters, TickPoses};
use std::sync::{Arc, Mutex, MutexGuard};

/// A pose sink shared between the tracker thread and another task (e.g. the status timer of the zenoh sink).
pub struct SharedSink<S: PoseSink> {
    name: String,
    inner: Arc<Mutex<S>>,
}

impl<S: PoseSink> SharedSink<S> {
    /// Wraps `inner`; its name is read once here.
    pub fn new(inner: Arc<Mutex<S>>) -> Self {
        let name = inner
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .name()
            .to_string();
        Self { name, inner }
    }

    fn lock(&self) -> MutexGuard<'_, S> {
        self.inner.lock().unwrap_or_else(|p| p.into_inner())
    }
}

impl<S: PoseSink> PoseSink for SharedSink<S> {
    fn name(&self) -> &str {
        &self.name
    }
    fn publish(&mut self, poses: &TickPoses<'_>) -> Result<(), PublishError> {
        self.lock().publish(poses)
    }
    fn counters(&self) -> SinkCounters {
        self.lock().counters()
    }
    fn flush(&mut self) -> Result<(), PublishError> {
        self.lock().flush()
    }
    fn revise(&mut self, revised: &[tracker::track::PoseEstimate]) {
        self.lock().revise(revised);
    }
}

//! Renders started on a helper thread ahead of the request that reads them, for a backend that renders on the
//! caller's thread (the CPU renderer).
//!
//! The tracker asks, once a tick's poses are out, for the next tick's ROI at the pose that tick will predict. A
//! forked renderer on the `render-ahead` thread renders it while the tracker waits for the next tick, and the
//! next tick's request takes the finished image by swapping buffers. An image is taken only by a bit-identical
//! request (scene, lighting, flags, camera), and the fork renders exactly as the renderer itself, so rendering ahead
//! never changes what a render returns. Any other request renders on the caller's thread as before.

mod helper;
mod request;
#[cfg(test)]
mod tests;

use super::{MeshId, PrefetchCounts, RenderDevice, RenderError, RenderTarget, Renderer, Scene};
use crate::geometry::{PinholeCamera, Roi};
use crate::mesh::Mesh;
use helper::{Helper, Job};
use request::AheadRequest;
use std::sync::Arc;
use std::sync::mpsc::TrySendError;

/// Renders kept ahead at most (each slot holds a ROI's `RenderTarget`, about 0.6 MB at 160x160): up to eight objects
/// stepped by one thread, each at the two microseconds its next tick may fall on. Past that, a prefetch waits for
/// the oldest render and replaces it.
const AHEAD_SLOTS: usize = 16;

/// A renderer that also renders ahead on a helper thread ([`Renderer::prefetch_roi`]): a decorator of any
/// backend that can [`Renderer::fork`]. Renders on request go to the wrapped renderer on the caller's thread.
///
/// The helper thread starts at the first prefetch (so it inherits the caller's scheduling, e.g. the runtime's
/// `SCHED_FIFO`), and is restarted with a fresh fork after a mesh is added. It costs a second thread that renders
/// once per object and tick; results are bit-identical to the wrapped renderer's.
pub struct RenderAhead {
    inner: Box<dyn Renderer + Send>,
    helper: Option<Helper>,
    slots: Vec<Slot>,
    /// Prefetches so far (orders slots for replacement).
    sequence: u64,
    counts: PrefetchCounts,
}

/// A prefetched render's place: the request it answers and, unless the helper holds it, its job.
struct Slot {
    request: AheadRequest,
    /// `None` while the helper renders it.
    job: Option<Job>,
    /// Whether the slot holds a render not yet taken (in flight or finished).
    holds: bool,
    /// [`RenderAhead::sequence`] when it was started.
    started: u64,
}

impl std::fmt::Debug for RenderAhead {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RenderAhead")
            .field("helper_running", &self.helper.is_some())
            .field("slots", &self.slots.len())
            .field("counts", &self.counts)
            .finish_non_exhaustive()
    }
}

impl RenderAhead {
    /// `inner`, rendering ahead on a helper thread with a fork of it. If `inner` cannot fork, prefetches start
    /// nothing and every render is rendered on request.
    pub fn new(inner: Box<dyn Renderer + Send>) -> Self {
        Self {
            inner,
            helper: None,
            slots: Vec::new(),
            sequence: 0,
            counts: PrefetchCounts::default(),
        }
    }

    /// Starts the helper thread with a fork of the wrapped renderer, if it is not running; `false` if the renderer
    /// cannot fork or the thread cannot be spawned.
    fn ensure_helper(&mut self) -> bool {
        if self.helper.is_none()
            && let Some(renderer) = self.inner.fork()
        {
            self.helper = Helper::spawn(renderer, AHEAD_SLOTS).ok();
        }
        self.helper.is_some()
    }

    /// Puts a job the helper returned back into its slot.
    fn take_back(&mut self, job: Job) {
        if let Some(slot) = self.slots.get_mut(job.slot) {
            slot.job = Some(job);
        }
    }

    /// Takes back every job the helper has finished, without waiting.
    fn collect_finished(&mut self) {
        while let Some(job) = self.helper.as_ref().and_then(|h| h.done.try_recv().ok()) {
            self.take_back(job);
        }
    }

    /// Waits until slot `k`'s job is back; `false` if the helper thread is gone (its renders are then forgotten).
    fn wait_for(&mut self, k: usize) -> bool {
        while self.slots[k].job.is_none() {
            let received = match &self.helper {
                Some(h) => h.done.recv().ok(),
                None => None,
            };
            match received {
                Some(job) => self.take_back(job),
                None => {
                    self.stop_helper();
                    return false;
                }
            }
        }
        true
    }

    /// Stops the helper thread once it has rendered the jobs it was given; every render ahead is forgotten and its
    /// slot freed.
    fn stop_helper(&mut self) {
        if let Some(helper) = self.helper.take() {
            helper.stop(|job| {
                if let Some(slot) = self.slots.get_mut(job.slot) {
                    slot.job = Some(job);
                }
            });
        }
        for (k, slot) in self.slots.iter_mut().enumerate() {
            slot.holds = false;
            if slot.job.is_none() {
                slot.job = Some(Job::new(k));
            }
        }
    }

    /// A slot free for a new prefetch: an unused one, a new one, or the slot of the oldest render nobody took
    /// (waiting for it if it is still being rendered, so which render is replaced never depends on timing).
    fn free_slot(&mut self) -> Option<usize> {
        if let Some(k) = self.slots.iter().position(|s| !s.holds && s.job.is_some()) {
            return Some(k);
        }
        if self.slots.len() < AHEAD_SLOTS {
            let k = self.slots.len();
            self.slots.push(Slot {
                request: AheadRequest::default(),
                job: Some(Job::new(k)),
                holds: false,
                started: 0,
            });
            return Some(k);
        }
        let oldest = self
            .slots
            .iter()
            .enumerate()
            .min_by_key(|(_, s)| s.started)
            .map(|(k, _)| k)?;
        self.wait_for(oldest).then_some(oldest)
    }
}

impl Drop for RenderAhead {
    fn drop(&mut self) {
        self.stop_helper();
    }
}

impl Renderer for RenderAhead {
    fn device(&self) -> RenderDevice {
        self.inner.device()
    }

    fn add_mesh(&mut self, mesh: Arc<Mesh>) -> Result<MeshId, RenderError> {
        // The helper's fork would not know the mesh: the next prefetch forks again.
        self.stop_helper();
        self.inner.add_mesh(mesh)
    }

    fn render(
        &mut self,
        scene: &Scene<'_>,
        camera: &PinholeCamera,
        target: &mut RenderTarget,
    ) -> Result<(), RenderError> {
        let ahead = self
            .slots
            .iter()
            .position(|s| s.holds && s.request.is(scene, camera));
        if let Some(k) = ahead
            && self.wait_for(k)
        {
            let slot = &mut self.slots[k];
            slot.holds = false;
            if let Some(job) = slot.job.as_mut()
                && job.result.is_ok()
            {
                std::mem::swap(target, &mut job.target);
                self.counts.used += 1;
                return Ok(());
            }
            // A failed render ahead is rendered again here, which reports its error.
        }
        self.inner.render(scene, camera, target)
    }

    fn prefetch_roi(
        &mut self,
        scene: &Scene<'_>,
        camera: &PinholeCamera,
        roi: &Roi,
    ) -> Result<bool, RenderError> {
        let camera = camera.crop(roi);
        if !self.ensure_helper() {
            return Ok(false);
        }
        self.collect_finished();
        if self
            .slots
            .iter()
            .any(|s| s.holds && s.request.is(scene, &camera))
        {
            return Ok(true);
        }
        let Some(k) = self.free_slot() else {
            return Ok(false);
        };
        let slot = &mut self.slots[k];
        let Some(mut job) = slot.job.take() else {
            return Ok(false);
        };
        slot.request.assign(scene, &camera);
        job.request.copy_from(&slot.request);
        job.result = Ok(());
        let sent = match &self.helper {
            Some(h) => h.jobs.try_send(job),
            None => Err(TrySendError::Disconnected(job)),
        };
        match sent {
            Ok(()) => {
                self.sequence += 1;
                let slot = &mut self.slots[k];
                slot.holds = true;
                slot.started = self.sequence;
                self.counts.started += 1;
                Ok(true)
            }
            Err(TrySendError::Full(job) | TrySendError::Disconnected(job)) => {
                self.slots[k].job = Some(job);
                self.slots[k].holds = false;
                self.stop_helper();
                Ok(false)
            }
        }
    }

    fn prefetch_counts(&self) -> PrefetchCounts {
        self.counts
    }

    fn forget_prefetched(&mut self) {
        // A job still on the helper thread frees its slot when it comes back.
        for slot in &mut self.slots {
            slot.holds = false;
        }
    }

    fn renders_ahead(&self) -> bool {
        true
    }

    /// A renderer for another thread that renders ahead on its own helper thread.
    fn fork(&self) -> Option<Box<dyn Renderer + Send>> {
        Some(Box::new(Self::new(self.inner.fork()?)))
    }
}

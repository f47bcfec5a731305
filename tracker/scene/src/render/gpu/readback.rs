//! A helper thread that waits for prefetched renders and unpacks them into CPU memory, so the image is ready when
//! the tick that asks for it starts: the tick then only swaps render targets.

use super::frame::{padded_row_bytes, unpack};
use crate::geometry::PinholeCamera;
use crate::render::RenderTarget;
use std::sync::mpsc::{Receiver, SyncSender, sync_channel};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::thread::JoinHandle;

/// Result slot of a readback buffer's map request.
pub(super) type MapResult = Arc<Mutex<Option<Result<(), wgpu::BufferAsyncError>>>>;

/// Waits for `submission` (or finds it done), unpacks the image `camera` sees from the mapped `readback` buffer
/// into `target` and releases the mapping. The error says what failed (without the adapter's name).
pub(super) fn read_back(
    device: &wgpu::Device,
    readback: &wgpu::Buffer,
    mapped: &MapResult,
    submission: Option<wgpu::SubmissionIndex>,
    camera: &PinholeCamera,
    target: &mut RenderTarget,
) -> Result<(), String> {
    let polled = device.poll(wgpu::PollType::Wait {
        submission_index: submission,
        timeout: None,
    });
    let map_result = mapped.lock().ok().and_then(|mut slot| slot.take());
    polled.map_err(|e| format!("waiting for the GPU failed: {e}"))?;
    match map_result {
        Some(Ok(())) => {}
        Some(Err(e)) => return Err(format!("reading the image back failed: {e}")),
        None => return Err("the image read-back never completed".into()),
    }
    let (w, h) = (camera.width, camera.height);
    let row_bytes = padded_row_bytes(w);
    let slice = readback.slice(..u64::from(row_bytes) * u64::from(h));
    target.reset(w, h);
    target.camera = Some(*camera);
    let unpacked = slice
        .get_mapped_range()
        .map(|view| unpack(&view, row_bytes as usize, target))
        .map_err(|e| format!("mapping the read-back buffer failed: {e}"));
    readback.unmap();
    unpacked
}

/// The unpacked image of one prefetch slot, shared with the helper thread.
#[derive(Debug, Default)]
pub(super) struct Unpacked {
    state: Mutex<UnpackState>,
    changed: Condvar,
}

#[derive(Debug, Default)]
struct UnpackState {
    /// The image, once unpacked (swapped with the caller's target when taken).
    target: RenderTarget,
    /// Whether a job for this slot is queued or running.
    pending: bool,
    /// The job's outcome: `Err` names what failed.
    result: Option<Result<(), String>>,
}

impl Unpacked {
    fn lock(&self) -> Result<MutexGuard<'_, UnpackState>, String> {
        self.state
            .lock()
            .map_err(|_| "the read-back thread failed while unpacking".to_owned())
    }

    /// Marks a job as queued for this slot.
    pub(super) fn begin(&self) -> Result<(), String> {
        let mut s = self.lock()?;
        s.pending = true;
        s.result = None;
        Ok(())
    }

    /// Waits for the slot's job and swaps its image into `target` (the slot keeps `target`'s old buffers).
    pub(super) fn take(&self, target: &mut RenderTarget) -> Result<(), String> {
        let mut s = self.wait()?;
        match s.result.take() {
            Some(Ok(())) => {
                std::mem::swap(target, &mut s.target);
                Ok(())
            }
            Some(Err(e)) => Err(e),
            None => Err("the prefetched image was never read back".into()),
        }
    }

    /// Waits until no job for this slot is queued or running, and forgets its outcome.
    pub(super) fn settle(&self) -> Result<(), String> {
        self.wait()?.result = None;
        Ok(())
    }

    fn wait(&self) -> Result<MutexGuard<'_, UnpackState>, String> {
        let mut s = self.lock()?;
        while s.pending {
            s = self
                .changed
                .wait(s)
                .map_err(|_| "the read-back thread failed while unpacking".to_owned())?;
        }
        Ok(s)
    }
}

/// One prefetched render to wait for and unpack.
pub(super) struct UnpackJob {
    pub(super) device: wgpu::Device,
    pub(super) readback: wgpu::Buffer,
    pub(super) mapped: MapResult,
    pub(super) submission: wgpu::SubmissionIndex,
    pub(super) camera: PinholeCamera,
    pub(super) into: Arc<Unpacked>,
}

impl UnpackJob {
    /// Waits, unpacks and reports the outcome to the slot; a panic in the device code is reported as an error,
    /// so a render waiting for this slot never waits forever.
    pub(super) fn run(self) {
        let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| self.unpack()))
            .unwrap_or_else(|_| Err("the read-back thread panicked while unpacking".into()));
        if let Ok(mut s) = self.into.state.lock() {
            s.result = Some(outcome);
            s.pending = false;
        }
        self.into.changed.notify_all();
    }

    fn unpack(&self) -> Result<(), String> {
        let mut s = self
            .into
            .state
            .lock()
            .map_err(|_| "the prefetch slot's image was poisoned".to_owned())?;
        read_back(
            &self.device,
            &self.readback,
            &self.mapped,
            Some(self.submission.clone()),
            &self.camera,
            &mut s.target,
        )
    }
}

/// The helper thread and its job queue (at most one job per prefetch slot). Dropping it ends the thread after
/// the queued jobs.
#[derive(Debug)]
pub(super) struct Unpacker {
    jobs: Option<SyncSender<UnpackJob>>,
    thread: Option<JoinHandle<()>>,
}

impl Unpacker {
    /// Starts the thread; `capacity` jobs can be queued without blocking.
    pub(super) fn start(capacity: usize) -> std::io::Result<Self> {
        let (jobs, queue): (_, Receiver<UnpackJob>) = sync_channel(capacity);
        let thread = std::thread::Builder::new()
            .name("gpu-readback".into())
            .spawn(move || {
                for job in queue {
                    job.run();
                }
            })?;
        Ok(Self {
            jobs: Some(jobs),
            thread: Some(thread),
        })
    }

    /// Queues `job`; gives it back if the thread has ended.
    pub(super) fn send(&self, job: UnpackJob) -> Result<(), UnpackJob> {
        match &self.jobs {
            Some(jobs) => jobs.send(job).map_err(|e| e.0),
            None => Err(job),
        }
    }
}

impl Drop for Unpacker {
    fn drop(&mut self) {
        self.jobs = None;
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

impl std::fmt::Debug for UnpackJob {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("UnpackJob")
            .field("camera", &self.camera)
            .finish_non_exhaustive()
    }
}

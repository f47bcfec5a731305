//! The `render-ahead` thread: renders the jobs it is handed with its own fork of the renderer and hands them back.

use super::request::AheadRequest;
use crate::render::{RenderError, RenderTarget, Renderer};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::mpsc::{Receiver, SyncSender, sync_channel};
use std::thread::JoinHandle;

/// A render handed to the helper thread and back: what to render and the buffers it renders into.
pub(super) struct Job {
    /// The slot the job belongs to.
    pub(super) slot: usize,
    pub(super) request: AheadRequest,
    pub(super) target: RenderTarget,
    pub(super) result: Result<(), RenderError>,
}

impl Job {
    /// An empty job of slot `slot`.
    pub(super) fn new(slot: usize) -> Self {
        Self {
            slot,
            request: AheadRequest::default(),
            target: RenderTarget::new(),
            result: Ok(()),
        }
    }
}

/// The running helper thread and its two channels, each bounded to `capacity` jobs (preallocated: sending and
/// receiving do not allocate).
pub(super) struct Helper {
    pub(super) jobs: SyncSender<Job>,
    pub(super) done: Receiver<Job>,
    thread: JoinHandle<()>,
}

impl Helper {
    /// Starts the thread with `renderer`. A panic while rendering is caught and returned as the job's error.
    pub(super) fn spawn(
        mut renderer: Box<dyn Renderer + Send>,
        capacity: usize,
    ) -> std::io::Result<Self> {
        let (jobs, todo) = sync_channel::<Job>(capacity);
        let (finished, done) = sync_channel::<Job>(capacity);
        let thread = std::thread::Builder::new()
            .name("render-ahead".into())
            .spawn(move || {
                while let Ok(mut job) = todo.recv() {
                    let scene = job.request.scene();
                    let camera = job.request.camera();
                    let target = &mut job.target;
                    let result = catch_unwind(AssertUnwindSafe(|| match camera {
                        Some(c) => renderer.render(&scene, &c, target),
                        None => Err(RenderError::Backend("render ahead without a camera".into())),
                    }));
                    job.result = result.unwrap_or_else(|_| {
                        Err(RenderError::Backend(
                            "the render-ahead thread panicked while rendering".into(),
                        ))
                    });
                    if finished.send(job).is_err() {
                        break;
                    }
                }
            })?;
        Ok(Self { jobs, done, thread })
    }

    /// Stops the thread once it has rendered the jobs it was given, passing each of them to `back`.
    pub(super) fn stop(self, mut back: impl FnMut(Job)) {
        let Self { jobs, done, thread } = self;
        drop(jobs);
        while let Ok(job) = done.recv() {
            back(job);
        }
        let _ = thread.join();
    }
}

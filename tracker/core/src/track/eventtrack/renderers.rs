//! The renderers a tick renders on: the tracker's own and a fork per object thread, with the threads that step
//! objects and check re-detection places beside the tracker's own.

use super::threads::ObjectThreads;
use crate::track::config::{DepthUse, TrackerConfig};
use scene::render::Renderer;

/// The tracker's renderer, its forks and the object threads that use them.
pub(super) struct Renderers {
    /// The tracker thread's renderer.
    pub main: Box<dyn Renderer + Send>,
    /// Forks of `main` for the threads that step objects beside the tracker's own
    /// ([`crate::track::ExecutionConfig::object_threads`]).
    pub workers: Vec<Box<dyn Renderer + Send>>,
    /// The threads the workers step objects and check places on (started at the first tick that needs them).
    pub threads: ObjectThreads,
}

impl Renderers {
    /// `main` and as many forks as `objects` objects and the re-detection checks of `config` can use, up to the
    /// configured (or available) threads.
    pub fn new(config: &TrackerConfig, objects: usize, main: Box<dyn Renderer + Send>) -> Self {
        let threads = match config.execution.object_threads {
            0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
            n => n,
        };
        // Threads step objects and check re-detection places; a single object's places are checked on several.
        let checks_at_once = match config.redetect {
            r if !r.enabled => 1,
            r if r.places_per_tick == 0 || config.modalities.depth == DepthUse::DepthFramesOnly => {
                threads
            }
            r => r.places_per_tick,
        };
        let workers = (1..threads.min(objects.max(checks_at_once)))
            .map_while(|_| main.fork())
            .collect();
        Self {
            main,
            workers,
            threads: ObjectThreads::default(),
        }
    }

    /// Every renderer, the tracker thread's first.
    pub fn all(&self) -> impl Iterator<Item = &Box<dyn Renderer + Send>> {
        std::iter::once(&self.main).chain(&self.workers)
    }

    /// Drops the renders prefetched and not taken.
    pub fn forget_prefetched(&mut self) {
        self.main.forget_prefetched();
        for w in &mut self.workers {
            w.forget_prefetched();
        }
    }
}

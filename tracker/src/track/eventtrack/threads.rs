//! The tracker's object threads: persistent threads that run a tick's parallel shares (object steps, re-detection
//! place checks) beside the tracker's own thread. They start at the first tick that needs them, on the tracker's
//! thread, so they inherit its scheduling (the runtime's `SCHED_FIFO`), and are woken per tick through bounded
//! channels: a tick spawns no thread and allocates nothing.

use std::any::Any;
use std::panic::{AssertUnwindSafe, catch_unwind, resume_unwind};
use std::sync::mpsc::{Receiver, SyncSender, sync_channel};
use std::thread::JoinHandle;

/// A pointer to data a tick's shares use, each share a disjoint part of it (the caller's promise, checked where
/// it is dereferenced).
pub(super) struct SharedMut<T: ?Sized>(*mut T);

impl<T: ?Sized> SharedMut<T> {
    /// Wraps `ptr`.
    pub(super) fn new(ptr: *mut T) -> Self {
        Self(ptr)
    }

    /// The pointer (a method, so that a closure captures the whole wrapper rather than its field).
    pub(super) fn get(&self) -> *mut T {
        self.0
    }
}

// SAFETY: only the pointer is shared; each share dereferences a part no other share touches.
unsafe impl<T: ?Sized> Send for SharedMut<T> {}
// SAFETY: as above.
unsafe impl<T: ?Sized> Sync for SharedMut<T> {}

/// One share of a tick's work: run `work(index)`.
struct Share {
    /// The tick's work, its lifetime erased: [`ObjectThreads::run`] does not return before every thread is done
    /// with it.
    work: *const (dyn Fn(usize) -> u64 + Sync + 'static),
    index: usize,
}

// SAFETY: `work` is `Sync` and outlives every use (see `Share::work`).
unsafe impl Send for Share {}

/// What a share returned, or the panic it raised.
type ShareResult = Result<u64, Box<dyn Any + Send>>;

/// A started object thread and its two channels.
struct ObjectThread {
    shares: SyncSender<Share>,
    done: Receiver<ShareResult>,
    handle: JoinHandle<()>,
}

/// Persistent threads for a tick's parallel shares; none until the first [`Self::run`] that needs them.
#[derive(Default)]
pub(super) struct ObjectThreads {
    threads: Vec<ObjectThread>,
}

impl std::fmt::Debug for ObjectThreads {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ObjectThreads")
            .field("started", &self.threads.len())
            .finish()
    }
}

impl ObjectThreads {
    /// Runs `work(0)` on this thread and `work(1)` to `work(others)` on as many object threads, and returns the
    /// sum of what they return. Returns only when every share is done; a panic in any share is resumed here
    /// after all have finished. Threads that cannot be started leave their shares to this thread.
    pub(super) fn run(&mut self, others: usize, work: &(dyn Fn(usize) -> u64 + Sync)) -> u64 {
        self.start(others);
        // SAFETY: only the lifetime is erased. Every share sent below is received back before this function
        // returns (or the thread that held it has ended), so no thread uses `work` after it.
        let erased: *const (dyn Fn(usize) -> u64 + Sync + 'static) = unsafe {
            std::mem::transmute::<
                *const (dyn Fn(usize) -> u64 + Sync + '_),
                *const (dyn Fn(usize) -> u64 + Sync + 'static),
            >(work)
        };
        let mut sent = 0;
        let mut on_this_thread = 0..0;
        for index in 1..=others {
            let handed = self.threads.get(index - 1).is_some_and(|t| {
                t.shares
                    .send(Share {
                        work: erased,
                        index,
                    })
                    .is_ok()
            });
            if handed {
                sent += 1;
            } else {
                on_this_thread = index..others + 1;
                break;
            }
        }
        let mut panic = None;
        let mut total = 0;
        for index in std::iter::once(0).chain(on_this_thread) {
            match catch_unwind(AssertUnwindSafe(|| work(index))) {
                Ok(n) => total += n,
                Err(p) => panic = panic.or(Some(p)),
            }
        }
        for t in &self.threads[..sent] {
            match t.done.recv() {
                Ok(Ok(n)) => total += n,
                Ok(Err(p)) => panic = panic.or(Some(p)),
                Err(_) => {
                    panic = panic.or(Some(Box::new("an object thread ended during a tick")));
                }
            }
        }
        if let Some(p) = panic {
            resume_unwind(p);
        }
        total
    }

    /// Starts object threads until there are `count` (or one cannot be started).
    fn start(&mut self, count: usize) {
        while self.threads.len() < count {
            let (shares, todo) = sync_channel::<Share>(1);
            let (finished, done) = sync_channel::<ShareResult>(1);
            let spawned = std::thread::Builder::new()
                .name(format!("objects-{}", self.threads.len() + 1))
                .spawn(move || {
                    while let Ok(share) = todo.recv() {
                        // SAFETY: `ObjectThreads::run` keeps `work` alive until this share's result is received.
                        let work = unsafe { &*share.work };
                        let result = catch_unwind(AssertUnwindSafe(|| work(share.index)));
                        if finished.send(result).is_err() {
                            break;
                        }
                    }
                });
            match spawned {
                Ok(handle) => self.threads.push(ObjectThread {
                    shares,
                    done,
                    handle,
                }),
                Err(_) => break,
            }
        }
    }
}

impl Drop for ObjectThreads {
    fn drop(&mut self) {
        for t in self.threads.drain(..) {
            drop(t.shares);
            let _ = t.handle.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Mutex;

    #[test]
    fn every_share_runs_once_on_its_own_thread_and_the_results_add_up() {
        let mut threads = ObjectThreads::default();
        for _ in 0..3 {
            let seen = Mutex::new(Vec::new());
            let total = threads.run(3, &|i| {
                seen.lock()
                    .unwrap()
                    .push((i, std::thread::current().name().map(str::to_owned)));
                10 * i as u64 + 1
            });
            assert_eq!(total, 1 + 11 + 21 + 31);
            let mut seen = seen.into_inner().unwrap();
            seen.sort();
            assert_eq!(seen.len(), 4);
            for (k, (i, name)) in seen.iter().enumerate() {
                assert_eq!(*i, k);
                if k > 0 {
                    assert_eq!(name.as_deref(), Some(format!("objects-{k}").as_str()));
                }
            }
        }
        assert_eq!(threads.threads.len(), 3);
    }

    #[test]
    fn a_panicking_share_is_resumed_after_every_share_is_done() {
        let mut threads = ObjectThreads::default();
        let done = Mutex::new(0);
        let result = catch_unwind(AssertUnwindSafe(|| {
            threads.run(2, &|i| {
                if i == 1 {
                    panic!("share 1 fails");
                }
                *done.lock().unwrap() += 1;
                0
            })
        }));
        assert!(result.is_err());
        assert_eq!(*done.lock().unwrap(), 2);
        // The threads survive it.
        assert_eq!(threads.run(2, &|i| i as u64), 3);
    }
}

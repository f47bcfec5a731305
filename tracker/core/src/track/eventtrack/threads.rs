//! The tracker's object threads: persistent threads that run a tick's parallel shares (object steps, re-detection
//! place checks) beside the tracker's own thread. They start at the first tick that needs them, on the tracker's
//! thread, so they inherit its scheduling (the runtime's `SCHED_FIFO`), and are woken per tick through bounded
//! channels: a tick spawns no thread and allocates nothing.

use scene::render::Renderer;
use std::any::Any;
use std::marker::PhantomData;
use std::ops::Range;
use std::panic::{AssertUnwindSafe, catch_unwind, resume_unwind};
use std::sync::mpsc::{Receiver, SyncSender, sync_channel};
use std::thread::JoinHandle;

/// The shares a tick handed to object threads and has not received back yet. Its drop receives the rest, so that
/// `ObjectThreads::run` cannot return, or unwind, while a thread still runs the tick's work.
struct Outstanding<'a> {
    threads: &'a [ObjectThread],
    sent: usize,
    received: usize,
}

impl Outstanding<'_> {
    /// The next thread's result (`None` inside if that thread has ended), or `None` once all are received.
    fn next(&mut self) -> Option<Option<ShareResult>> {
        let t = self
            .threads
            .get(self.received)
            .filter(|_| self.received < self.sent)?;
        self.received += 1;
        Some(t.done.recv().ok())
    }
}

impl Drop for Outstanding<'_> {
    fn drop(&mut self) {
        while self.next().is_some() {}
    }
}

/// A slice a tick's shares each take a disjoint range of ([`Self::range`]), from threads of their own.
pub(super) struct ShareSlice<'a, T> {
    ptr: *mut T,
    len: usize,
    _borrow: PhantomData<&'a mut [T]>,
}

impl<'a, T> ShareSlice<'a, T> {
    /// Shares `items` for as long as they are borrowed here.
    pub(super) fn new(items: &'a mut [T]) -> Self {
        Self {
            ptr: items.as_mut_ptr(),
            len: items.len(),
            _borrow: PhantomData,
        }
    }

    /// `items[range]`. Panics if the range is out of bounds.
    ///
    /// # Safety
    /// Ranges taken while another is in use must be disjoint from it.
    #[allow(clippy::mut_from_ref)]
    pub(super) unsafe fn range(&self, range: Range<usize>) -> &'a mut [T] {
        assert!(
            range.start <= range.end && range.end <= self.len,
            "{range:?} of {}",
            self.len
        );
        // SAFETY: in bounds (checked above) of a slice borrowed mutably for 'a; the caller keeps ranges disjoint.
        unsafe {
            std::slice::from_raw_parts_mut(self.ptr.add(range.start), range.end - range.start)
        }
    }
}

// SAFETY: only disjoint ranges are handed out (the promise of `range`), each to one thread.
unsafe impl<T: Send> Send for ShareSlice<'_, T> {}
// SAFETY: as above.
unsafe impl<T: Send> Sync for ShareSlice<'_, T> {}

/// The renderers of a tick split into shares: share 0 renders with the tracker thread's own renderer, share
/// `i > 0` with worker `i - 1`.
pub(super) struct ShareRenderers<'a> {
    own: *mut (dyn Renderer + 'a),
    workers: ShareSlice<'a, Box<dyn Renderer + Send>>,
}

impl<'a> ShareRenderers<'a> {
    /// Shares `own` and `workers` for as long as they are borrowed here.
    pub(super) fn new(
        own: &'a mut dyn Renderer,
        workers: &'a mut [Box<dyn Renderer + Send>],
    ) -> Self {
        Self {
            own,
            workers: ShareSlice::new(workers),
        }
    }

    /// The renderer of share `i`. Panics if there is none (`i` greater than the number of workers).
    ///
    /// # Safety
    /// No two shares in use at once may take the same `i`.
    #[allow(clippy::mut_from_ref)]
    pub(super) unsafe fn get(&self, i: usize) -> &'a mut dyn Renderer {
        if i == 0 {
            // SAFETY: borrowed mutably for 'a; share 0 alone takes it (the caller's promise).
            unsafe { &mut *self.own }
        } else {
            // SAFETY: worker `i - 1` alone, taken by share `i` alone (the caller's promise).
            unsafe { self.workers.range(i - 1..i)[0].as_mut() }
        }
    }
}

// SAFETY: each renderer is taken by one share at a time (the promise of `get`). Share 0, which takes the own
// renderer, runs on the tracker's thread that lent it.
unsafe impl Send for ShareRenderers<'_> {}
// SAFETY: as above.
unsafe impl Sync for ShareRenderers<'_> {}

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
        // returns, by the loop below or, if anything unwinds first, by `Outstanding`'s drop (or the thread that
        // held it has ended), so no thread uses `work` after it.
        let erased: *const (dyn Fn(usize) -> u64 + Sync + 'static) = unsafe {
            std::mem::transmute::<
                *const (dyn Fn(usize) -> u64 + Sync + '_),
                *const (dyn Fn(usize) -> u64 + Sync + 'static),
            >(work)
        };
        let mut outstanding = Outstanding {
            threads: &self.threads,
            received: 0,
            sent: 0,
        };
        let mut on_this_thread = 0..0;
        for index in 1..=others {
            let handed = outstanding.threads.get(index - 1).is_some_and(|t| {
                t.shares
                    .send(Share {
                        work: erased,
                        index,
                    })
                    .is_ok()
            });
            if handed {
                outstanding.sent += 1;
            } else {
                on_this_thread = index..others + 1;
                break;
            }
        }
        let mut panic = None;
        let mut total = 0u64;
        let keep_first =
            |p: Box<dyn Any + Send>, panic: &mut Option<Box<dyn Any + Send>>| match panic {
                None => *panic = Some(p),
                // A later payload is dropped where a panic in its own drop cannot escape.
                Some(_) => drop(catch_unwind(AssertUnwindSafe(move || drop(p)))),
            };
        for index in std::iter::once(0).chain(on_this_thread) {
            match catch_unwind(AssertUnwindSafe(|| work(index))) {
                Ok(n) => total = total.wrapping_add(n),
                Err(p) => keep_first(p, &mut panic),
            }
        }
        while let Some(result) = outstanding.next() {
            match result {
                Some(Ok(n)) => total = total.wrapping_add(n),
                Some(Err(p)) => keep_first(p, &mut panic),
                None => keep_first(Box::new("an object thread ended during a tick"), &mut panic),
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
            let ObjectThread {
                shares,
                done,
                handle,
            } = t;
            drop(shares);
            drop(done);
            let _ = handle.join();
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

    #[test]
    fn sums_wrap_instead_of_unwinding_while_threads_run_and_later_ticks_get_their_own_results() {
        let mut threads = ObjectThreads::default();
        assert_eq!(threads.run(2, &|_| u64::MAX), u64::MAX.wrapping_mul(3));
        for k in 0..3u64 {
            assert_eq!(threads.run(2, &|i| i as u64 + k), 3 + 3 * k);
        }
    }
}

//! Traffic counters of a server, readable while it runs.

use std::sync::atomic::{AtomicU64, Ordering};

/// Live counters, updated by the server's threads.
#[derive(Debug, Default)]
pub(crate) struct Counters {
    submitted: AtomicU64,
    completed: AtomicU64,
    unlinked: AtomicU64,
    bytes_in: AtomicU64,
    bytes_out: AtomicU64,
    pending_in: AtomicU64,
}

/// The counters at one moment. Totals run over every session of the server.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CounterSnapshot {
    /// `CMD_SUBMIT`s received.
    pub submitted: u64,
    /// `RET_SUBMIT`s sent (success or error), counted as each is written.
    pub completed: u64,
    /// Requests cancelled by `CMD_UNLINK` while queued (answered `-ECONNRESET`).
    pub unlinked: u64,
    /// Data bytes sent to the host (in transfers, control included).
    pub bytes_in: u64,
    /// Data bytes received from the host (out transfers, control included).
    pub bytes_out: u64,
    /// Bulk-in requests queued now, waiting for device data.
    pub pending_in: u64,
}

impl Counters {
    pub(crate) fn submitted(&self) {
        self.submitted.fetch_add(1, Ordering::Relaxed);
    }

    pub(crate) fn completed(&self, bytes_in: usize) {
        self.completed.fetch_add(1, Ordering::Relaxed);
        self.bytes_in.fetch_add(bytes_in as u64, Ordering::Relaxed);
    }

    pub(crate) fn unlinked(&self) {
        self.unlinked.fetch_add(1, Ordering::Relaxed);
    }

    pub(crate) fn received(&self, bytes_out: usize) {
        self.bytes_out
            .fetch_add(bytes_out as u64, Ordering::Relaxed);
    }

    pub(crate) fn set_pending(&self, pending: usize) {
        self.pending_in.store(pending as u64, Ordering::Relaxed);
    }

    pub(crate) fn snapshot(&self) -> CounterSnapshot {
        CounterSnapshot {
            submitted: self.submitted.load(Ordering::Relaxed),
            completed: self.completed.load(Ordering::Relaxed),
            unlinked: self.unlinked.load(Ordering::Relaxed),
            bytes_in: self.bytes_in.load(Ordering::Relaxed),
            bytes_out: self.bytes_out.load(Ordering::Relaxed),
            pending_in: self.pending_in.load(Ordering::Relaxed),
        }
    }
}

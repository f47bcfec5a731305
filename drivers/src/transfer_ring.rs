//! A bounded ring of byte chunks between a device's transfer callbacks (producer) and a stream decoder
//! (consumer). The producer never blocks: when every slot is full, the chunk is dropped and counted, and the next
//! chunk delivered is marked as following a gap so the decoder resynchronises. Slots are allocated once; steady
//! state allocates nothing.

use std::collections::VecDeque;
use std::sync::{Condvar, Mutex, MutexGuard};
use std::time::Duration;

/// Counters of a ring, for status and summaries.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RingCounters {
    /// Chunks accepted.
    pub chunks: u64,
    /// Bytes accepted.
    pub bytes: u64,
    /// Chunks dropped because every slot was full.
    pub dropped_chunks: u64,
    /// Bytes of the dropped chunks.
    pub dropped_bytes: u64,
    /// The most slots ever filled at once.
    pub max_filled: usize,
}

/// One chunk taken from the ring; give its buffer back with [`TransferRing::recycle`].
#[derive(Debug)]
pub struct Chunk {
    /// The bytes, as the device sent them.
    pub bytes: Vec<u8>,
    /// Whether chunks were dropped just before this one (the stream has a gap here).
    pub after_gap: bool,
}

struct State {
    filled: VecDeque<Chunk>,
    free: Vec<Vec<u8>>,
    gap_pending: bool,
    closed: bool,
    counters: RingCounters,
}

/// The ring. Shared between the producer and the consumer (wrap it in an `Arc`).
pub struct TransferRing {
    state: Mutex<State>,
    ready: Condvar,
    slots: usize,
    slot_bytes: usize,
}

impl TransferRing {
    /// A ring of `slots` chunks of up to `slot_bytes` bytes each (`slots * slot_bytes` bytes of memory).
    pub fn new(slots: usize, slot_bytes: usize) -> Self {
        let slots = slots.max(1);
        Self {
            state: Mutex::new(State {
                filled: VecDeque::with_capacity(slots),
                free: (0..slots).map(|_| Vec::with_capacity(slot_bytes)).collect(),
                gap_pending: false,
                closed: false,
                counters: RingCounters::default(),
            }),
            ready: Condvar::new(),
            slots,
            slot_bytes,
        }
    }

    fn lock(&self) -> MutexGuard<'_, State> {
        // A panic while holding the lock cannot leave the ring's state half-updated in a way that matters to
        // the other side: keep going with it.
        self.state.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Memory held by the slots, bytes.
    pub fn memory_bytes(&self) -> usize {
        self.slots * self.slot_bytes
    }

    /// Copies `bytes` into a free slot, or drops and counts them when none is free. Never blocks on the consumer.
    /// Returns whether the chunk was kept. Chunks longer than a slot are kept whole (the slot grows once).
    pub fn push(&self, bytes: &[u8]) -> bool {
        if bytes.is_empty() {
            return true;
        }
        let mut s = self.lock();
        let Some(mut buf) = s.free.pop() else {
            s.counters.dropped_chunks += 1;
            s.counters.dropped_bytes += bytes.len() as u64;
            s.gap_pending = true;
            return false;
        };
        buf.clear();
        buf.extend_from_slice(bytes);
        let after_gap = std::mem::take(&mut s.gap_pending);
        s.filled.push_back(Chunk {
            bytes: buf,
            after_gap,
        });
        s.counters.chunks += 1;
        s.counters.bytes += bytes.len() as u64;
        s.counters.max_filled = s.counters.max_filled.max(s.filled.len());
        drop(s);
        self.ready.notify_one();
        true
    }

    /// Marks a gap the producer knows of (a failed transfer) so the next chunk is flagged.
    pub fn mark_gap(&self) {
        self.lock().gap_pending = true;
    }

    /// Takes the oldest chunk, waiting up to `timeout` for one; `None` on timeout or when closed and empty.
    pub fn pop(&self, timeout: Duration) -> Option<Chunk> {
        let mut s = self.lock();
        if s.filled.is_empty() && !s.closed {
            s = self
                .ready
                .wait_timeout_while(s, timeout, |s| s.filled.is_empty() && !s.closed)
                .map_or_else(|p| p.into_inner().0, |(g, _)| g);
        }
        s.filled.pop_front()
    }

    /// Gives a chunk's buffer back to the producer.
    pub fn recycle(&self, chunk: Chunk) {
        let mut s = self.lock();
        if s.free.len() + s.filled.len() < self.slots {
            s.free.push(chunk.bytes);
        }
    }

    /// Wakes a waiting consumer for good: [`pop`](Self::pop) returns `None` once the ring is empty.
    pub fn close(&self) {
        self.lock().closed = true;
        self.ready.notify_all();
    }

    /// Whether [`close`](Self::close) was called.
    pub fn is_closed(&self) -> bool {
        self.lock().closed
    }

    /// The counters so far.
    pub fn counters(&self) -> RingCounters {
        self.lock().counters
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn a_full_ring_drops_counts_and_flags_the_gap() {
        let ring = TransferRing::new(2, 4);
        assert!(ring.push(b"ab"));
        assert!(ring.push(b"cd"));
        assert!(!ring.push(b"efg"));
        let c = ring.counters();
        assert_eq!(
            (c.chunks, c.bytes, c.dropped_chunks, c.dropped_bytes),
            (2, 4, 1, 3)
        );
        let a = ring.pop(Duration::ZERO).unwrap();
        assert_eq!((a.bytes.as_slice(), a.after_gap), (&b"ab"[..], false));
        ring.recycle(a);
        assert!(ring.push(b"hi"));
        let b = ring.pop(Duration::ZERO).unwrap();
        assert!(!b.after_gap);
        ring.recycle(b);
        let h = ring.pop(Duration::ZERO).unwrap();
        assert_eq!((h.bytes.as_slice(), h.after_gap), (&b"hi"[..], true));
        assert_eq!(ring.memory_bytes(), 8);
    }

    #[test]
    fn a_closed_ring_wakes_its_consumer() {
        let ring = std::sync::Arc::new(TransferRing::new(1, 4));
        let r = ring.clone();
        let t = std::thread::spawn(move || r.pop(Duration::from_secs(30)).is_none());
        std::thread::sleep(Duration::from_millis(20));
        ring.close();
        assert!(t.join().unwrap());
    }

    proptest! {
        /// Every byte pushed is either delivered, in order, or counted as dropped, and exactly the first chunk
        /// kept after a run of drops is flagged as following a gap.
        #[test]
        fn nothing_is_lost_silently(ops in proptest::collection::vec((any::<bool>(), 1usize..40), 1..200), slots in 1usize..6) {
            let ring = TransferRing::new(slots, 16);
            let (mut sent, mut delivered) = (Vec::new(), Vec::new());
            let (mut flags_expected, mut flags_seen) = (Vec::new(), Vec::new());
            let (mut dropped, mut dropping, mut next) = (0u64, false, 0u8);
            let take = |ring: &TransferRing, delivered: &mut Vec<u8>, flags_seen: &mut Vec<bool>| {
                let Some(c) = ring.pop(Duration::ZERO) else { return false };
                flags_seen.push(c.after_gap);
                delivered.extend_from_slice(&c.bytes);
                ring.recycle(c);
                true
            };
            for (produce, n) in ops {
                if produce {
                    let bytes: Vec<u8> = (0..n).map(|_| { next = next.wrapping_add(1); next }).collect();
                    if ring.push(&bytes) {
                        sent.extend_from_slice(&bytes);
                        flags_expected.push(std::mem::take(&mut dropping));
                    } else {
                        dropped += n as u64;
                        dropping = true;
                    }
                } else {
                    take(&ring, &mut delivered, &mut flags_seen);
                }
            }
            while take(&ring, &mut delivered, &mut flags_seen) {}
            prop_assert_eq!(&delivered, &sent);
            prop_assert_eq!(&flags_seen, &flags_expected);
            prop_assert_eq!(ring.counters().dropped_bytes, dropped);
        }
    }
}

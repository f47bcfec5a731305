//! The bounded queue between ingest (sources) and the tracker thread.
//!
//! Overload policy (DESIGN section 3): event batches are bounded; when the queue is full the OLDEST event batch
//! is dropped and every event in it counted. Trigger edges and depth frames are never dropped (they are few and
//! carry the timeline). The tracker thread never blocks on a producer. Event buffers are recycled through a pool
//! so steady-state ingest does not allocate.

use drivers::event::{CdEvent, TriggerEdge};
use drivers::recording::DepthFrame;
use std::collections::VecDeque;
use std::sync::{Condvar, Mutex, MutexGuard};
use std::time::{Duration, Instant};

/// One item of ingest, in stream order.
#[derive(Debug)]
pub enum Ingest {
    /// CD events in time order.
    Events(Vec<CdEvent>),
    /// A trigger edge and the wall-clock instant it was decoded (start of the latency measurement).
    Trigger {
        /// The edge.
        edge: TriggerEdge,
        /// When it was decoded.
        decoded_at: Instant,
    },
    /// A depth frame and its exposure time on the event camera's clock.
    Depth {
        /// Exposure time, microseconds (the phase-coded pulse's rising edge).
        t_us: i64,
        /// The frame.
        frame: Box<DepthFrame>,
    },
    /// The source has ended (or was stopped): the tracker thread finishes the timeline and exits.
    End,
}

/// Drop counters of the queue.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct QueueCounters {
    /// Event batches dropped under overload.
    pub dropped_batches: u64,
    /// Events in those batches.
    pub dropped_events: u64,
    /// Event batches accepted.
    pub batches: u64,
    /// Events accepted.
    pub events: u64,
    /// Most event batches waiting at once.
    pub max_depth: usize,
}

#[derive(Debug, Default)]
struct State {
    items: VecDeque<Ingest>,
    event_batches: usize,
    counters: QueueCounters,
    pool: Vec<Vec<CdEvent>>,
}

/// A bounded multi-producer, single-consumer ingest queue with the drop-oldest policy.
#[derive(Debug)]
pub struct IngestQueue {
    state: Mutex<State>,
    ready: Condvar,
    space: Condvar,
    capacity: usize,
    batch_capacity: usize,
}

/// Buffers kept in the pool at most.
const POOL_MAX: usize = 64;

impl IngestQueue {
    /// A queue holding at most `capacity` event batches of `batch_capacity` events (preallocated buffers).
    pub fn new(capacity: usize, batch_capacity: usize) -> Self {
        let capacity = capacity.max(1);
        let pool = (0..capacity.min(POOL_MAX))
            .map(|_| Vec::with_capacity(batch_capacity))
            .collect();
        Self {
            state: Mutex::new(State {
                items: VecDeque::with_capacity(capacity + 64),
                pool,
                ..State::default()
            }),
            ready: Condvar::new(),
            space: Condvar::new(),
            capacity,
            batch_capacity,
        }
    }

    fn lock(&self) -> MutexGuard<'_, State> {
        // A panic while holding the lock cannot leave the queue inconsistent (every update is one step).
        self.state.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// An empty event buffer from the pool (allocates only when the pool is empty).
    pub fn buffer(&self) -> Vec<CdEvent> {
        self.lock()
            .pool
            .pop()
            .unwrap_or_else(|| Vec::with_capacity(self.batch_capacity))
    }

    /// Returns a consumed buffer to the pool.
    pub fn recycle(&self, mut buf: Vec<CdEvent>) {
        buf.clear();
        let mut s = self.lock();
        if s.pool.len() < POOL_MAX {
            s.pool.push(buf);
        }
    }

    /// Pushes an item without ever blocking: a full queue drops its oldest event batch (counted).
    pub fn push(&self, item: Ingest) {
        let mut s = self.lock();
        if let Ingest::Events(ev) = &item {
            if ev.is_empty() {
                return;
            }
            if s.event_batches >= self.capacity
                && let Some(i) = s.items.iter().position(|x| matches!(x, Ingest::Events(_)))
                && let Some(Ingest::Events(mut old)) = s.items.remove(i)
            {
                s.event_batches -= 1;
                s.counters.dropped_batches += 1;
                s.counters.dropped_events += old.len() as u64;
                old.clear();
                if s.pool.len() < POOL_MAX {
                    s.pool.push(old);
                }
            }
            s.event_batches += 1;
            s.counters.batches += 1;
            s.counters.events += ev.len() as u64;
            s.counters.max_depth = s.counters.max_depth.max(s.event_batches);
        }
        s.items.push_back(item);
        drop(s);
        self.ready.notify_one();
    }

    /// Pushes an item, waiting while the queue holds `capacity` event batches (fast replay: no drops).
    pub fn push_wait(&self, item: Ingest) {
        if matches!(item, Ingest::Events(_)) {
            let mut s = self.lock();
            while s.event_batches >= self.capacity {
                s = self
                    .space
                    .wait_timeout(s, Duration::from_millis(50))
                    .map(|r| r.0)
                    .unwrap_or_else(|p| p.into_inner().0);
            }
        }
        self.push(item);
    }

    /// The next item, waiting at most `timeout`; `None` when nothing arrived.
    pub fn pop(&self, timeout: Duration) -> Option<Ingest> {
        let mut s = self.lock();
        if s.items.is_empty() {
            s = self
                .ready
                .wait_timeout(s, timeout)
                .map(|r| r.0)
                .unwrap_or_else(|p| p.into_inner().0);
        }
        let item = s.items.pop_front()?;
        if matches!(item, Ingest::Events(_)) {
            s.event_batches -= 1;
            drop(s);
            self.space.notify_one();
        }
        Some(item)
    }

    /// Counters so far.
    pub fn counters(&self) -> QueueCounters {
        self.lock().counters
    }

    /// Items waiting (all kinds).
    pub fn len(&self) -> usize {
        self.lock().items.len()
    }

    /// Whether nothing is waiting.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn batch(q: &IngestQueue, t: i64, n: usize) -> Ingest {
        let mut b = q.buffer();
        b.extend((0..n).map(|i| CdEvent {
            t_us: t + i as i64,
            ..CdEvent::default()
        }));
        Ingest::Events(b)
    }

    fn edge(t: i64) -> Ingest {
        Ingest::Trigger {
            edge: TriggerEdge {
                t_us: t,
                channel: 0,
                rising: true,
            },
            decoded_at: Instant::now(),
        }
    }

    #[test]
    fn overload_drops_oldest_batches_and_keeps_edges() {
        let q = IngestQueue::new(4, 16);
        q.push(batch(&q, 0, 3));
        q.push(edge(5));
        for k in 1..=5 {
            q.push(batch(&q, k * 100, 2));
        }
        // 6 batches into 4 slots: the two oldest (3 + 2 events) went; the edge stayed, in order.
        let c = q.counters();
        assert_eq!((c.dropped_batches, c.dropped_events), (2, 5));
        assert_eq!((c.batches, c.events), (6, 13));
        let mut seen = Vec::new();
        while let Some(item) = q.pop(Duration::from_millis(1)) {
            seen.push(match item {
                Ingest::Events(e) => e[0].t_us,
                Ingest::Trigger { edge, .. } => -edge.t_us,
                _ => unreachable!(),
            });
        }
        assert_eq!(seen, vec![-5, 200, 300, 400, 500]);
        assert!(q.is_empty());
    }

    #[test]
    fn pop_times_out_when_empty_and_buffers_recycle() {
        let q = IngestQueue::new(4, 8);
        let t = Instant::now();
        assert!(q.pop(Duration::from_millis(20)).is_none());
        assert!(t.elapsed() >= Duration::from_millis(15));
        let b = q.buffer();
        let cap = b.capacity();
        q.recycle(b);
        assert_eq!(q.buffer().capacity(), cap);
    }

    #[test]
    fn push_wait_blocks_until_the_consumer_makes_room() {
        let q = std::sync::Arc::new(IngestQueue::new(4, 8));
        for k in 0..4 {
            q.push(batch(&q, k, 1));
        }
        let q2 = q.clone();
        let producer = std::thread::spawn(move || {
            let b = batch(&q2, 99, 1);
            q2.push_wait(b);
        });
        std::thread::sleep(Duration::from_millis(30));
        assert_eq!(q.len(), 4, "the producer must wait, not drop");
        assert!(q.pop(Duration::from_millis(1)).is_some());
        producer.join().unwrap();
        assert_eq!(q.counters().dropped_batches, 0);
        assert_eq!(q.len(), 4);
    }
}

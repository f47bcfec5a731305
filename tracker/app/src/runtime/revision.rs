//! Poses of published ticks that the tracker revised: when a depth frame arrives after ticks since its exposure
//! were published, EventTrack6D tracks those ticks again with it. Their revised estimates go to the sinks
//! ([`PoseSink::revise`]), so that the zenoh pose queries answer with them.

use crate::publish::PoseSink;
use std::collections::VecDeque;
use tracker::track::{MAX_DEPTH_AGE_LIMIT_MS, PoseEstimate, PoseTracker};

/// Published ticks remembered, at most: 533 ms at 120 Hz, beyond the oldest depth frame the tracker may be
/// configured to use ([`MAX_DEPTH_AGE_LIMIT_MS`]).
const REMEMBERED_TICKS: usize = 64;

// At 120 Hz (8333 us ticks) and slower, that covers the oldest depth frame plus the tick it is used at.
const _: () =
    assert!(REMEMBERED_TICKS as f64 * 8_333.0 >= MAX_DEPTH_AGE_LIMIT_MS * 1_000.0 + 8_333.0);

/// The latest published estimates, and what the tracker reported it tracked again.
#[derive(Debug)]
pub(super) struct PoseRevisions {
    /// The estimates of the latest [`REMEMBERED_TICKS`] published ticks, oldest first.
    published: VecDeque<PoseEstimate>,
    /// Objects per tick.
    objects: usize,
    /// Scratch for the revised estimates (kept between calls: no allocation in steady state).
    revised: Vec<PoseEstimate>,
    /// Revised estimates handed to the sinks so far.
    handed: u64,
}

impl PoseRevisions {
    /// Room for `objects` objects, allocated now.
    pub(super) fn new(objects: usize) -> Self {
        let capacity = REMEMBERED_TICKS * objects.max(1);
        Self {
            published: VecDeque::with_capacity(capacity),
            objects: objects.max(1),
            revised: Vec::with_capacity(capacity),
            handed: 0,
        }
    }

    /// Remembers one tick's published estimates. Estimates at or after their time (a clock that went back) are
    /// forgotten first.
    pub(super) fn published(&mut self, estimates: &[PoseEstimate]) {
        let Some(t_us) = estimates.first().map(|e| e.t_us) else {
            return;
        };
        while self.published.back().is_some_and(|e| e.t_us >= t_us) {
            self.published.pop_back();
        }
        for e in estimates {
            if self.published.len() == REMEMBERED_TICKS * self.objects {
                self.published.pop_front();
            }
            self.published.push_back(*e);
        }
    }

    /// Hands `sinks` the revised estimate of every published tick at or after `since_us`, the earliest tick the
    /// tracker says it revised ([`PoseTracker::take_revision`]). Only the pose is revised: quality and state stay
    /// as published (the tracker keeps no per-tick quality). Returns how many estimates were handed.
    pub(super) fn revise(
        &mut self,
        since_us: i64,
        tracker: &dyn PoseTracker,
        sinks: &mut [Box<dyn PoseSink>],
    ) -> usize {
        self.revised.clear();
        for e in self.published.iter().filter(|e| e.t_us >= since_us) {
            if let Some(now) = tracker.pose_at(e.object, e.t_us) {
                self.revised.push(PoseEstimate {
                    pose: now.pose,
                    ..*e
                });
            }
        }
        if !self.revised.is_empty() {
            for sink in sinks.iter_mut() {
                sink.revise(&self.revised);
            }
        }
        self.handed += self.revised.len() as u64;
        self.revised.len()
    }

    /// Revised estimates handed to the sinks so far.
    pub(super) fn handed(&self) -> u64 {
        self.handed
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::publish::{PublishError, SinkCounters, TickPoses};
    use drivers::event::CdEvent;
    use drivers::recording::DepthFrame;
    use drivers::timeline::Tick;
    use nalgebra::{Isometry3, Translation3};
    use std::sync::{Arc, Mutex};
    use tracker::track::{DepthHandling, TrackingState};

    /// Two objects; `pose_at` answers x = the time in seconds (+1 once "tracked again"); a depth frame makes it
    /// say it revised the ticks from half a period before the frame's exposure (the tick nearest it) on.
    struct Retracking {
        names: Vec<String>,
        retracked: u64,
        revised_since: Option<i64>,
    }

    impl PoseTracker for Retracking {
        fn objects(&self) -> &[String] {
            &self.names
        }
        fn push_events(&mut self, _: &[CdEvent]) {}
        fn push_depth(&mut self, t_us: i64, _: &mut DepthFrame, _: DepthHandling) {
            self.retracked += 1;
            self.revised_since = Some(t_us - 4_167);
        }
        fn take_revision(&mut self) -> Option<i64> {
            self.revised_since.take()
        }
        fn tick(&mut self, tick: &Tick, out: &mut Vec<PoseEstimate>) {
            for object in 0..self.names.len() {
                out.push(PoseEstimate {
                    object,
                    t_us: tick.t_us,
                    pose: Isometry3::identity(),
                    quality: 0.25,
                    state: TrackingState::Degraded,
                });
            }
        }
        fn pose_at(&self, object: usize, t_us: i64) -> Option<PoseEstimate> {
            (object < 2).then(|| PoseEstimate {
                object,
                t_us,
                pose: Isometry3::from_parts(
                    Translation3::new(t_us as f64 * 1e-6 + self.retracked as f64, 0.0, 0.5),
                    Default::default(),
                ),
                quality: 0.9,
                state: TrackingState::Tracking,
            })
        }
    }

    struct Revisions(Arc<Mutex<Vec<PoseEstimate>>>);

    impl PoseSink for Revisions {
        fn name(&self) -> &str {
            "revisions"
        }
        fn publish(&mut self, _: &TickPoses<'_>) -> Result<(), PublishError> {
            Ok(())
        }
        fn counters(&self) -> SinkCounters {
            SinkCounters::default()
        }
        fn revise(&mut self, revised: &[PoseEstimate]) {
            self.0.lock().unwrap().extend_from_slice(revised);
        }
    }

    #[test]
    fn ticks_since_the_revision_are_revised_with_the_trackers_poses() {
        let mut tracker = Retracking {
            names: vec!["a".into(), "b".into()],
            retracked: 0,
            revised_since: None,
        };
        let got = Arc::new(Mutex::new(Vec::new()));
        let mut sinks: Vec<Box<dyn PoseSink>> = vec![Box::new(Revisions(got.clone()))];
        let mut revisions = PoseRevisions::new(2);
        let published = |t_us: i64, object: usize| PoseEstimate {
            object,
            t_us,
            pose: Isometry3::identity(),
            quality: 0.25,
            state: TrackingState::Degraded,
        };
        for k in 0..76 {
            let t = 500 + k * 8_333;
            revisions.published(&[published(t, 0), published(t, 1)]);
        }
        // Nothing tracked again: nothing revised.
        assert_eq!(tracker.take_revision(), None);
        // Tracked again from the frame exposed at 601_000 us, 0.5 ms after the tick at 600_476 (where the tracker
        // starts): that tick and the three after it (the last of the 64 remembered), each object once.
        let mut frame = DepthFrame {
            index: 9,
            width: 0,
            height: 0,
            depth_m: Vec::new(),
        };
        tracker.push_depth(601_000, &mut frame, DepthHandling::Now);
        let since = tracker.take_revision().unwrap();
        assert_eq!(revisions.revise(since, &tracker, &mut sinks), 8);
        let got = got.lock().unwrap().clone();
        let times: Vec<(usize, i64)> = got.iter().map(|e| (e.object, e.t_us)).collect();
        assert_eq!(
            times,
            [
                (0, 600_476),
                (1, 600_476),
                (0, 608_809),
                (1, 608_809),
                (0, 617_142),
                (1, 617_142),
                (0, 625_475),
                (1, 625_475)
            ]
        );
        // The pose is the tracker's; quality and state stay as published.
        assert!((got[0].pose.translation.x - 1.600_476).abs() < 1e-9);
        assert_eq!(
            (got[0].quality, got[0].state),
            (0.25, TrackingState::Degraded)
        );
        assert_eq!(revisions.handed(), 8);
        // Taken once: no second revision.
        assert_eq!(tracker.take_revision(), None);
        // A clock that went back forgets the ticks after it; 64 ticks of two objects are kept at most.
        revisions.published(&[published(300_000, 0), published(300_000, 1)]);
        assert!(revisions.published.iter().all(|e| e.t_us <= 300_000));
        assert!(revisions.published.capacity() >= REMEMBERED_TICKS * 2);
    }

    #[test]
    fn the_worker_hands_the_revisions_to_its_sinks_and_counts_them() {
        use crate::runtime::health::Health;
        use crate::runtime::queue::{Ingest, IngestQueue};
        use crate::runtime::worker::Worker;
        use drivers::timeline::{TimelineConfig, ideal_edges};
        use std::time::Instant;

        let cfg = TimelineConfig::default();
        let names = vec!["a".to_string(), "b".to_string()];
        let queue = Arc::new(IngestQueue::new(64, 16));
        let health = Arc::new(Mutex::new(Health::new(&names, &["revisions".into()])));
        let got = Arc::new(Mutex::new(Vec::new()));
        let tracker = Retracking {
            names: names.clone(),
            retracked: 0,
            revised_since: None,
        };
        let worker = Worker::new(
            Box::new(tracker),
            vec![Box::new(Revisions(got.clone()))],
            cfg,
            queue.clone(),
            health.clone(),
        );
        let thread = std::thread::spawn(move || worker.run());
        let edges = ideal_edges(&cfg, 1000, 16);
        let rising: Vec<i64> = edges.iter().filter(|e| e.rising).map(|e| e.t_us).collect();
        // The frame exposed at the fifth tick arrives after the ninth edge pair.
        let exposure = rising[4];
        for (k, e) in edges.iter().enumerate() {
            queue.push(Ingest::Trigger {
                edge: *e,
                decoded_at: Instant::now(),
            });
            if k == 17 {
                queue.push(Ingest::Depth {
                    t_us: exposure,
                    frame: Box::new(DepthFrame {
                        index: 1,
                        width: 0,
                        height: 0,
                        depth_m: Vec::new(),
                    }),
                });
            }
        }
        queue.push(Ingest::End);
        thread.join().unwrap();
        let got = got.lock().unwrap().clone();
        assert!(!got.is_empty(), "nothing revised");
        assert!(got.iter().all(|e| e.t_us >= exposure), "{got:?}");
        assert!(
            got.iter().any(|e| e.t_us == exposure),
            "the exposure's own tick is revised"
        );
        assert!(
            got.iter()
                .all(|e| (e.quality, e.state) == (0.25, TrackingState::Degraded))
        );
        assert_eq!(got.iter().filter(|e| e.object == 0).count(), got.len() / 2);
        let h = health.lock().unwrap();
        assert_eq!(h.poses_revised, got.len() as u64);
        assert_eq!(
            h.status_json("finished")["ingest"]["poses_revised"],
            got.len() as u64
        );
    }
}

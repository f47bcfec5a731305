//! Poses of published ticks that the tracker revised: when a depth frame arrives after ticks since its exposure
//! were published, EventTrack6D tracks those ticks again with it. Their revised estimates go to the sinks
//! ([`PoseSink::revise`]), so that the zenoh pose queries answer with them.

use crate::publish::PoseSink;
use crate::track::{PoseEstimate, PoseTracker};
use std::collections::VecDeque;

/// Published ticks remembered, at most: 266 ms at 120 Hz, beyond any depth frame the tracker still uses.
const REMEMBERED_TICKS: usize = 32;

/// The times of the latest published ticks, and what the tracker reported it tracked again.
#[derive(Debug)]
pub(super) struct PoseRevisions {
    /// Times of the latest published ticks, oldest first, microseconds.
    ticks: VecDeque<i64>,
    /// Scratch for the revised estimates (kept between calls: no allocation in steady state).
    revised: Vec<PoseEstimate>,
    /// The tracker's count of late frames it tracked again from, when last looked at.
    retracked_frames: u64,
    /// Revised estimates handed to the sinks so far.
    handed: u64,
}

impl PoseRevisions {
    /// Room for `objects` objects, allocated now.
    pub(super) fn new(objects: usize) -> Self {
        Self {
            ticks: VecDeque::with_capacity(REMEMBERED_TICKS),
            revised: Vec::with_capacity(REMEMBERED_TICKS * objects.max(1)),
            retracked_frames: 0,
            handed: 0,
        }
    }

    /// Remembers that the tick at `t_us` was published.
    pub(super) fn published(&mut self, t_us: i64) {
        if self.ticks.len() == REMEMBERED_TICKS {
            self.ticks.pop_front();
        }
        self.ticks.push_back(t_us);
    }

    /// After `tracker` worked on the depth frame exposed at `exposure_us`: if it tracked ticks again from it,
    /// hands every object's estimate at each published tick since the exposure to `sinks`. Returns how many.
    pub(super) fn after_depth(
        &mut self,
        exposure_us: i64,
        tracker: &dyn PoseTracker,
        sinks: &mut [Box<dyn PoseSink>],
    ) -> usize {
        let Some(counters) = tracker.tracker_counters() else {
            return 0;
        };
        if counters.late_frames_retracked == self.retracked_frames {
            return 0;
        }
        self.retracked_frames = counters.late_frames_retracked;
        self.revised.clear();
        for &t_us in self.ticks.iter().filter(|&&t| t >= exposure_us) {
            for object in 0..tracker.objects().len() {
                if let Some(estimate) = tracker.pose_at(object, t_us) {
                    self.revised.push(estimate);
                }
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
    use crate::track::{TrackerCounters, TrackingState};
    use drivers::event::CdEvent;
    use drivers::recording::DepthFrame;
    use drivers::timeline::Tick;
    use nalgebra::{Isometry3, Translation3};
    use std::sync::{Arc, Mutex};

    /// Two objects; `pose_at` answers x = the time in seconds (+1 once "tracked again"); the counters say how
    /// many late frames it tracked again from.
    struct Retracking {
        names: Vec<String>,
        retracked: u64,
    }

    impl PoseTracker for Retracking {
        fn objects(&self) -> &[String] {
            &self.names
        }
        fn push_events(&mut self, _: &[CdEvent]) {}
        fn push_depth(&mut self, _: i64, _: &mut DepthFrame) {
            self.retracked += 1;
        }
        fn tick(&mut self, _: &Tick, _: &mut Vec<PoseEstimate>) {}
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
        fn tracker_counters(&self) -> Option<TrackerCounters> {
            Some(TrackerCounters {
                late_frames_retracked: self.retracked,
                ..TrackerCounters::default()
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
    fn ticks_since_the_exposure_are_revised_only_when_the_tracker_tracked_again() {
        let mut tracker = Retracking {
            names: vec!["a".into(), "b".into()],
            retracked: 0,
        };
        let got = Arc::new(Mutex::new(Vec::new()));
        let mut sinks: Vec<Box<dyn PoseSink>> = vec![Box::new(Revisions(got.clone()))];
        let mut revisions = PoseRevisions::new(2);
        for k in 0..40 {
            revisions.published(500 + k * 8_333);
        }
        // Nothing tracked again: nothing revised.
        assert_eq!(revisions.after_depth(250_000, &tracker, &mut sinks), 0);
        // Tracked again from the frame exposed at 300_000 us: the ticks at or after it (500 + 36..=39 x 8_333 us,
        // all among the 32 remembered), each object once.
        let mut frame = DepthFrame {
            index: 9,
            width: 0,
            height: 0,
            depth_m: Vec::new(),
        };
        tracker.push_depth(300_000, &mut frame);
        assert_eq!(revisions.after_depth(300_000, &tracker, &mut sinks), 8);
        let got = got.lock().unwrap().clone();
        let times: Vec<(usize, i64)> = got.iter().map(|e| (e.object, e.t_us)).collect();
        assert_eq!(
            times,
            [
                (0, 300_488),
                (1, 300_488),
                (0, 308_821),
                (1, 308_821),
                (0, 317_154),
                (1, 317_154),
                (0, 325_487),
                (1, 325_487)
            ]
        );
        assert!((got[0].pose.translation.x - 1.300_488).abs() < 1e-9);
        assert_eq!(revisions.handed(), 8);
        // The same counters again: no second revision.
        assert_eq!(revisions.after_depth(300_000, &tracker, &mut sinks), 0);
    }
}

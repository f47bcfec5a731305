//! The recent events of an [`EventSurface`], each with what its pixel held before it: the surface can be wound
//! back to an earlier time and brought forward again event by event, to the same state. The tracker uses it to
//! track again from a late depth frame's exposure with the events as they were at each tick since.

use drivers::event::CdEvent;
use std::collections::VecDeque;

/// One integrated event and its pixel's state before it.
#[derive(Debug, Clone, Copy)]
pub(super) struct LoggedEvent {
    pub(super) event: CdEvent,
    /// The pixel's stored time offset before the event.
    pub(super) previous_time: i32,
    /// The pixel's log intensity before the event (0 for a surface that keeps times only).
    pub(super) previous_intensity: f32,
}

/// A bounded log of the events integrated through [`EventSurface::integrate_logged`]. Each event has a position:
/// how many events were logged before it. The surface can be wound back to any position the log still holds
/// (the oldest events go first once `capacity` is reached, or when forgotten) and forward again to its latest.
/// Grows to the events it must hold once, then allocates no more.
#[derive(Debug, Clone)]
pub struct SurfaceLog {
    pub(super) entries: VecDeque<LoggedEvent>,
    capacity: usize,
    /// Position of `entries[0]`; positions before it cannot be reached.
    pub(super) first: u64,
    /// Position up to which the events are applied to the surface (the end of the log unless wound back).
    pub(super) applied: u64,
    /// Events that left the log because it was full.
    overflowed: u64,
}

impl SurfaceLog {
    /// An empty log of at most `capacity` events.
    pub fn new(capacity: usize) -> Self {
        Self {
            entries: VecDeque::new(),
            capacity,
            first: 0,
            applied: 0,
            overflowed: 0,
        }
    }

    /// Events in the log.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether the log holds no event.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Events that left the log because it was full.
    pub fn overflowed(&self) -> u64 {
        self.overflowed
    }

    /// The position after the latest event: where the surface is when every logged event is applied.
    pub fn end(&self) -> u64 {
        self.first + self.entries.len() as u64
    }

    /// The position after the latest logged event at or before `t_us` (events are logged in time order); the
    /// start of the log when none is.
    pub fn position_after(&self, t_us: i64) -> u64 {
        self.first + self.entries.partition_point(|e| e.event.t_us <= t_us) as u64
    }

    /// Whether the surface can be wound back to `position`.
    pub fn reaches(&self, position: u64) -> bool {
        (self.first..=self.end()).contains(&position)
    }

    /// Whether every logged event is applied (the surface is at its latest state).
    pub fn at_latest(&self) -> bool {
        self.applied == self.end()
    }

    /// Forgets the events before `position`: the surface need not be wound back further than that.
    pub fn forget_before(&mut self, position: u64) {
        let n = position.min(self.applied).saturating_sub(self.first) as usize;
        self.entries.drain(..n);
        self.first += n as u64;
    }

    /// Forgets every event (the surface's stored times were rebased): no earlier position can be reached.
    pub(super) fn restart(&mut self) {
        self.first = self.end();
        self.entries.clear();
        self.applied = self.first;
    }

    /// Logs `entry`, the oldest leaving once the log is full.
    pub(super) fn push(&mut self, entry: LoggedEvent) {
        if self.entries.len() >= self.capacity {
            self.overflowed += 1;
            if self.entries.pop_front().is_none() {
                // No room at all: the event is applied, and nothing before it can be reached.
                self.first += 1;
                self.applied += 1;
                return;
            }
            self.first += 1;
        }
        self.entries.push_back(entry);
        self.applied += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recon::EventSurface;
    use crate::recon::IntensityFilterConfig;
    use proptest::prelude::*;

    fn event(t_us: i64, x: u16, y: u16, polarity: bool) -> CdEvent {
        CdEvent {
            t_us,
            x,
            y,
            polarity,
        }
    }

    fn state(s: &EventSurface) -> (Vec<i32>, Vec<u32>) {
        (
            s.last_us.clone(),
            s.log_intensity.iter().map(|v| v.to_bits()).collect(),
        )
    }

    #[test]
    fn wound_back_the_surface_is_as_it_was_and_forward_again_as_it_is() {
        let mut s = EventSurface::new(8, 4, IntensityFilterConfig::default());
        let mut log = SurfaceLog::new(100);
        s.integrate_logged(&[event(10, 1, 1, true), event(20, 2, 1, false)], &mut log);
        let at_two = state(&s);
        assert_eq!(log.end(), 2);
        s.integrate_logged(
            &[
                event(30, 1, 1, false),
                event(40, 2, 1, true),
                event(50, 3, 3, true),
            ],
            &mut log,
        );
        let at_five = state(&s);
        assert!(s.wind_back(&mut log, 2));
        assert_eq!(state(&s), at_two);
        assert_eq!(s.last_event_us(1, 1), Some(10));
        assert!(!log.at_latest());
        s.wind_forward(&mut log, 4);
        assert_eq!(s.last_event_us(2, 1), Some(40));
        assert_eq!(s.last_event_us(3, 3), None);
        s.wind_forward(&mut log, u64::MAX);
        assert!(log.at_latest());
        assert_eq!(state(&s), at_five);
        // Counted once, when they came.
        assert_eq!(s.events(), 5);
    }

    #[test]
    fn a_full_log_drops_its_oldest_events_and_no_longer_reaches_before_them() {
        let mut s = EventSurface::new(8, 4, IntensityFilterConfig::default());
        let mut log = SurfaceLog::new(2);
        s.integrate_logged(
            &[
                event(10, 1, 1, true),
                event(20, 2, 1, true),
                event(30, 3, 1, true),
            ],
            &mut log,
        );
        assert_eq!((log.len(), log.end(), log.overflowed()), (2, 3, 1));
        assert!(!log.reaches(0));
        assert!(log.reaches(1));
        let before = state(&s);
        assert!(!s.wind_back(&mut log, 0), "the first event is gone");
        assert_eq!(state(&s), before, "a refused wind-back changes nothing");
        assert!(s.wind_back(&mut log, 1));
        assert_eq!(s.last_event_us(2, 1), None);
        assert_eq!(s.last_event_us(1, 1), Some(10));
    }

    #[test]
    fn forgotten_events_cannot_be_undone() {
        let mut s = EventSurface::new(8, 4, IntensityFilterConfig::default());
        let mut log = SurfaceLog::new(10);
        s.integrate_logged(&[event(10, 1, 1, true), event(20, 2, 1, true)], &mut log);
        log.forget_before(1);
        assert_eq!(log.len(), 1);
        assert!(!log.reaches(0));
        assert!(s.wind_back(&mut log, 1));
        assert_eq!(s.last_event_us(1, 1), Some(10));
        assert_eq!(s.last_event_us(2, 1), None);
    }

    #[test]
    fn events_outside_the_sensor_are_counted_not_logged() {
        let mut s = EventSurface::new(8, 4, IntensityFilterConfig::default());
        let mut log = SurfaceLog::new(10);
        s.integrate_logged(&[event(10, 8, 1, true), event(20, 1, 4, true)], &mut log);
        assert!(log.is_empty());
        assert_eq!(s.out_of_bounds(), 2);
    }

    proptest! {
        /// Any stream integrated in any chunks, wound back to any position: the surface that integrated only the
        /// events before it; wound forward: the surface that integrated them all, bit for bit.
        #[test]
        fn wind_back_and_forward_match_plain_integration(
            raw in prop::collection::vec((0i64..400, 0u16..10, 0u16..6, any::<bool>()), 0..200),
            chunk in 1usize..20,
            split in 0usize..200,
            times_only in any::<bool>(),
        ) {
            let mut t = 0;
            let events: Vec<CdEvent> = raw
                .iter()
                .map(|&(dt, x, y, p)| {
                    t += dt;
                    event(t, x, y, p)
                })
                .collect();
            let new = || if times_only {
                EventSurface::latest_times_only(8, 5)
            } else {
                EventSurface::new(8, 5, IntensityFilterConfig::default())
            };
            let mut logged = new();
            let mut log = SurfaceLog::new(1000);
            for c in events.chunks(chunk) {
                logged.integrate_logged(c, &mut log);
            }
            let mut all = new();
            all.integrate(&events);
            // Positions count the events inside the sensor (8 x 5 here).
            let inside: Vec<CdEvent> = events.iter().copied().filter(|e| e.x < 8 && e.y < 5).collect();
            let split = split.min(inside.len());
            let mut before_split = new();
            before_split.integrate(&inside[..split]);
            prop_assert!(logged.wind_back(&mut log, split as u64));
            prop_assert_eq!(state(&logged), state(&before_split));
            logged.wind_forward(&mut log, u64::MAX);
            prop_assert_eq!(state(&logged), state(&all));
            prop_assert_eq!(logged.out_of_bounds(), all.out_of_bounds());
        }
    }
}

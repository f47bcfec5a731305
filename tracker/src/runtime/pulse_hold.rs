//! Holding back the events that arrive while a trigger pulse is open, so that at every tick the tracker has seen
//! exactly the events up to the tick's time, whatever the batching of the source.
//!
//! A tick is stamped with its pulse's rising edge but the timeline only emits it at the falling edge, because the
//! pulse width carries the depth phase code. Events decoded in between (up to the wide pulse's width, 200 us by
//! default) are after the tick; handed over at once they would reach the tick's estimate, which the offline
//! driver ([`crate::track::track_recording`]) never does, and [`PoseTracker::push_events`] forbids. Both drivers
//! give the tracker the same input.

use crate::track::PoseTracker;
use drivers::event::{CdEvent, TriggerEdge};

/// Events held while a pulse on the tick channel is open. Steady state does not allocate once the buffer has
/// grown to the largest pulse's event count.
#[derive(Debug)]
pub struct PulseHold {
    channel: u8,
    open: bool,
    held: Vec<CdEvent>,
}

impl PulseHold {
    /// A hold for pulses on trigger `channel` (the timeline's tick channel).
    pub fn new(channel: u8) -> Self {
        Self {
            channel,
            open: false,
            held: Vec::with_capacity(1 << 14),
        }
    }

    /// Events from the source, in time order: handed to `tracker` now, or held while a pulse is open.
    pub fn events(&mut self, events: &[CdEvent], tracker: &mut dyn PoseTracker) {
        if self.open {
            self.held.extend_from_slice(events);
        } else {
            tracker.push_events(events);
        }
    }

    /// Before the tick at `t_us` is estimated: hands over the held events at or before `t_us`.
    pub fn release_until(&mut self, t_us: i64, tracker: &mut dyn PoseTracker) {
        let split = self.held.partition_point(|e| e.t_us <= t_us);
        if split > 0 {
            tracker.push_events(&self.held[..split]);
            self.held.drain(..split);
        }
    }

    /// After the ticks that `edge` completed were estimated: a falling edge on the tick channel closes the pulse
    /// and hands over what was held; a rising edge opens one (handing over anything still held from a pulse
    /// whose falling edge was lost, since it is all before this edge).
    pub fn edge(&mut self, edge: &TriggerEdge, tracker: &mut dyn PoseTracker) {
        if edge.channel != self.channel {
            return;
        }
        self.release_all(tracker);
        self.open = edge.rising;
    }

    /// Hands over everything held (end of stream) and closes the pulse.
    pub fn release_all(&mut self, tracker: &mut dyn PoseTracker) {
        if !self.held.is_empty() {
            tracker.push_events(&self.held);
            self.held.clear();
        }
        self.open = false;
    }

    /// Events held now.
    pub fn held(&self) -> usize {
        self.held.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::track::PoseEstimate;
    use drivers::recording::DepthFrame;
    use drivers::timeline::Tick;

    /// Records the timestamps of the events it is handed.
    #[derive(Default)]
    struct Seen(Vec<i64>);

    impl PoseTracker for Seen {
        fn objects(&self) -> &[String] {
            &[]
        }
        fn push_events(&mut self, events: &[CdEvent]) {
            self.0.extend(events.iter().map(|e| e.t_us));
        }
        fn push_depth(&mut self, _: i64, _: &mut DepthFrame) {}
        fn tick(&mut self, _: &Tick, _: &mut Vec<PoseEstimate>) {}
        fn pose_at(&self, _: usize, _: i64) -> Option<PoseEstimate> {
            None
        }
    }

    fn ev(t_us: i64) -> CdEvent {
        CdEvent {
            t_us,
            ..CdEvent::default()
        }
    }

    fn edge(t_us: i64, channel: u8, rising: bool) -> TriggerEdge {
        TriggerEdge {
            t_us,
            channel,
            rising,
        }
    }

    #[test]
    fn events_inside_a_pulse_wait_for_its_tick() {
        let mut hold = PulseHold::new(0);
        let mut seen = Seen::default();
        hold.events(&[ev(90), ev(100)], &mut seen);
        hold.edge(&edge(100, 0, true), &mut seen);
        hold.events(&[ev(100), ev(150), ev(260)], &mut seen);
        assert_eq!(seen.0, [90, 100]);
        assert_eq!(hold.held(), 3);
        // The tick at the rising edge takes the event stamped with its own time, not the later ones.
        hold.release_until(100, &mut seen);
        assert_eq!(seen.0, [90, 100, 100]);
        hold.edge(&edge(300, 0, false), &mut seen);
        assert_eq!(seen.0, [90, 100, 100, 150, 260]);
        hold.events(&[ev(310)], &mut seen);
        assert_eq!(seen.0.last(), Some(&310));
        assert_eq!(hold.held(), 0);
    }

    #[test]
    fn other_channels_and_lost_falling_edges_do_not_hold_events_forever() {
        let mut hold = PulseHold::new(0);
        let mut seen = Seen::default();
        hold.edge(&edge(10, 1, true), &mut seen);
        hold.events(&[ev(20)], &mut seen);
        assert_eq!(seen.0, [20], "a pulse on another channel holds nothing");
        hold.edge(&edge(30, 0, true), &mut seen);
        hold.events(&[ev(40)], &mut seen);
        // The falling edge of that pulse never comes; the next rising edge hands over what was held.
        hold.edge(&edge(8363, 0, true), &mut seen);
        assert_eq!(seen.0, [20, 40]);
        hold.events(&[ev(8400)], &mut seen);
        hold.release_all(&mut seen);
        assert_eq!(seen.0, [20, 40, 8400]);
    }
}

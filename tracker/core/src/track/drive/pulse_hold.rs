//! Holding back the events that arrive while a trigger pulse is open or overdue, so that at every tick the tracker
//! has seen exactly the events up to the tick's time, whatever the batching of the source.
//!
//! A tick is stamped with its pulse's rising edge but the timeline only emits it at the falling edge, because the
//! pulse width carries the depth phase code. Events decoded in between (up to the wide pulse's width, 200 us by
//! default) are after the tick; handed over at once they would reach the tick's estimate, which
//! [`PoseTracker::push_events`] forbids.
//!
//! A pulse can also go missing. The timeline learns so only at the next pulse, and then places a tick between
//! the two. So events from the time the next pulse was due are held too, until a pulse comes: handed over at
//! once, they would reach the tick placed in the gap, which saw none of them offline. Normally the pulse comes
//! within its jitter of that time and the hold merely starts a little early ([`super::TickDriver`] sets the due
//! time the timeline's jitter tolerance, 50 us, ahead, so a tick placed in a gap a little before the schedule also sees
//! only earlier events). The hold keeps at most [`MAX_OVERDUE_EVENTS`]; beyond that the held events are handed over and the
//! overflow is counted.

use crate::track::PoseTracker;
use drivers::event::{CdEvent, TriggerEdge};

/// Most events held (64 MiB of events), while a pulse is open or overdue: about 0.1-1 s of a busy event camera.
/// A trigger that stops, open or closed, would otherwise hold events without end.
pub const MAX_OVERDUE_EVENTS: usize = 4 << 20;

/// Events held while a pulse on the tick channel is open or overdue. Steady state does not allocate once the
/// buffer has grown to the largest pulse's event count.
#[derive(Debug)]
pub struct PulseHold {
    channel: u8,
    open: bool,
    /// When the next pulse's rising edge is due (camera clock, microseconds): events from then on wait for it.
    due_us: Option<i64>,
    held: Vec<CdEvent>,
    overflows: u64,
}

impl PulseHold {
    /// A hold for pulses on trigger `channel` (the timeline's tick channel).
    pub fn new(channel: u8) -> Self {
        Self {
            channel,
            open: false,
            due_us: None,
            held: Vec::with_capacity(1 << 14),
            overflows: 0,
        }
    }

    /// Sets when the next pulse's rising edge is due ([`drivers::timeline::TriggerTimeline::next_pulse_due_us`]);
    /// `None` holds nothing until a pulse opens.
    pub fn set_due(&mut self, due_us: Option<i64>) {
        self.due_us = due_us;
    }

    /// Events from the source, in time order: handed to `tracker` now, or held while a pulse is open or overdue.
    pub fn events(&mut self, events: &[CdEvent], tracker: &mut dyn PoseTracker) {
        let split = if self.open || !self.held.is_empty() {
            0
        } else {
            match self.due_us {
                Some(due) => events.partition_point(|e| e.t_us < due),
                None => events.len(),
            }
        };
        if split > 0 {
            tracker.push_events(&events[..split]);
        }
        self.held.extend_from_slice(&events[split..]);
        if self.held.len() > MAX_OVERDUE_EVENTS {
            self.overflows += 1;
            self.release_events(tracker);
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

    /// After the ticks that `edge` completed were estimated: a falling edge on the tick channel closes the open
    /// pulse and hands over what was held; a rising edge opens one. What is held at a rising edge, or at a
    /// falling edge whose rising edge was lost, stays held: it may come after a tick the timeline has yet to
    /// place in a gap, and [`Self::release_until`] hands it over tick by tick.
    pub fn edge(&mut self, edge: &TriggerEdge, tracker: &mut dyn PoseTracker) {
        if edge.channel != self.channel {
            return;
        }
        if edge.rising {
            self.open = true;
        } else if self.open {
            self.release_all(tracker);
        }
    }

    /// Hands over everything held (end of stream) and closes the pulse.
    pub fn release_all(&mut self, tracker: &mut dyn PoseTracker) {
        self.release_events(tracker);
        self.open = false;
    }

    fn release_events(&mut self, tracker: &mut dyn PoseTracker) {
        if !self.held.is_empty() {
            tracker.push_events(&self.held);
            self.held.clear();
        }
    }

    /// Times an outage held more than [`MAX_OVERDUE_EVENTS`] and handed them over early.
    pub fn overflows(&self) -> u64 {
        self.overflows
    }

    /// Events held now.
    pub fn held(&self) -> usize {
        self.held.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::track::{DepthHandling, PoseEstimate};
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
        fn push_depth(&mut self, _: i64, _: &mut DepthFrame, _: DepthHandling) {}
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
        // The falling edge of that pulse never comes. At the next rising edge the timeline gives that pulse's
        // tick (at 30) and then, at the next pulse's end, its own (at 8363): each takes what came before it.
        hold.edge(&edge(8363, 0, true), &mut seen);
        hold.release_until(30, &mut seen);
        assert_eq!(seen.0, [20]);
        hold.events(&[ev(8400)], &mut seen);
        hold.release_until(8363, &mut seen);
        assert_eq!(seen.0, [20, 40]);
        hold.edge(&edge(8463, 0, false), &mut seen);
        assert_eq!(seen.0, [20, 40, 8400]);
        assert_eq!(hold.held(), 0);
    }

    #[test]
    fn events_after_a_missing_pulse_wait_for_the_tick_placed_in_its_gap() {
        let mut hold = PulseHold::new(0);
        let mut seen = Seen::default();
        // A pulse at 0 closed; the next is due at 8333 but never comes; the one after comes at 16667.
        hold.edge(&edge(0, 0, true), &mut seen);
        hold.edge(&edge(100, 0, false), &mut seen);
        hold.set_due(Some(8333));
        hold.events(&[ev(8000), ev(8333), ev(9000), ev(16000)], &mut seen);
        assert_eq!(
            seen.0,
            [8000],
            "only events before the due pulse go through"
        );
        hold.edge(&edge(16667, 0, true), &mut seen);
        hold.events(&[ev(16700)], &mut seen);
        // At that pulse's falling edge the timeline places a tick at 8333 in the gap, then the pulse's own.
        hold.release_until(8333, &mut seen);
        assert_eq!(seen.0, [8000, 8333]);
        hold.release_until(16667, &mut seen);
        assert_eq!(seen.0, [8000, 8333, 9000, 16000]);
        hold.edge(&edge(16767, 0, false), &mut seen);
        assert_eq!(seen.0, [8000, 8333, 9000, 16000, 16700]);
        assert_eq!(hold.overflows(), 0);
    }

    #[test]
    fn a_falling_edge_without_its_rising_edge_keeps_what_waits_for_a_gap() {
        let mut hold = PulseHold::new(0);
        let mut seen = Seen::default();
        hold.edge(&edge(0, 0, true), &mut seen);
        hold.edge(&edge(100, 0, false), &mut seen);
        hold.set_due(Some(8333));
        hold.events(&[ev(8000), ev(8400)], &mut seen);
        // The next pulse's rising edge is lost: its falling edge hands nothing over, since the timeline may
        // still place a tick before 8400.
        hold.edge(&edge(8433, 0, false), &mut seen);
        assert_eq!(seen.0, [8000]);
        hold.release_until(8333, &mut seen);
        assert_eq!(seen.0, [8000]);
        hold.release_until(16667, &mut seen);
        assert_eq!(seen.0, [8000, 8400]);
    }

    #[test]
    fn an_outage_holds_a_bounded_number_of_events() {
        let mut hold = PulseHold::new(0);
        let mut seen = Seen::default();
        hold.set_due(Some(0));
        let batch: Vec<CdEvent> = (0..1 << 16).map(ev).collect();
        for _ in 0..(MAX_OVERDUE_EVENTS >> 16) {
            hold.events(&batch, &mut seen);
        }
        assert_eq!(seen.0.len(), 0);
        assert_eq!(hold.held(), MAX_OVERDUE_EVENTS);
        hold.events(&batch[..1], &mut seen);
        assert_eq!(hold.overflows(), 1);
        assert_eq!(hold.held(), 0);
        assert_eq!(seen.0.len(), MAX_OVERDUE_EVENTS + 1);
    }
}

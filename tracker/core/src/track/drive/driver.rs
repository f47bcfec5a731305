//! The one tick driver: events and trigger edges in stream order in, a tracker fed exactly the events up to each
//! tick and the ticks out. The offline driver ([`super::track_recording_timed`]) and the runtime's tracker thread
//! both run on it, so a recording replayed in real time gives the poses offline tracking gives.

use super::pulse_hold::PulseHold;
use crate::track::PoseTracker;
use drivers::event::{CdEvent, TriggerEdge};
use drivers::timeline::{Tick, TimelineConfig, TimelineCounters, TriggerTimeline};

/// The trigger timeline with the event gate in front of the tracker.
///
/// Feed it in stream order: [`Self::events`] for events, [`Self::edge`] for a trigger edge followed by
/// [`Self::next_tick`] until it returns `None`, and [`Self::finish`] at the end of the stream followed by
/// [`Self::next_tick`] until `None`. Each tick [`Self::next_tick`] returns comes after the tracker was handed every
/// event at or before its time and none after; hand the tick's depth frames to the tracker and call
/// [`PoseTracker::tick`] before asking for the next.
#[derive(Debug)]
pub struct TickDriver {
    timeline: TriggerTimeline,
    hold: PulseHold,
    /// The latest edge, applied to the gate once the ticks it completed are out.
    pending_edge: Option<TriggerEdge>,
}

impl TickDriver {
    /// A driver for the trigger schedule `timeline`.
    pub fn new(timeline: TimelineConfig) -> Self {
        Self {
            timeline: TriggerTimeline::new(timeline),
            hold: PulseHold::new(timeline.channel),
            pending_edge: None,
        }
    }

    /// Events in time order: handed to `tracker` at once, or held while a tick pulse is open or overdue.
    pub fn events(&mut self, events: &[CdEvent], tracker: &mut dyn PoseTracker) {
        self.hold.events(events, tracker);
    }

    /// A trigger edge (any channel): the timeline places the ticks it completes; take them with
    /// [`Self::next_tick`] before the next call (a previous edge whose ticks were not all taken updates the gate
    /// here, handing `tracker` what it releases).
    pub fn edge(&mut self, edge: TriggerEdge, tracker: &mut dyn PoseTracker) {
        self.update_gate(tracker);
        self.timeline.push(edge);
        self.pending_edge = Some(edge);
    }

    /// The end of the stream: the timeline places its last ticks; take them with [`Self::next_tick`]. The events
    /// still held after them are no tick's: [`Self::release_held`] hands them over, for a caller that keeps the
    /// tracker's event state up to the end of the stream.
    pub fn finish(&mut self) {
        self.timeline.finish();
    }

    /// Hands `tracker` every event held (after the last tick, at the end of a stream) and closes the pulse.
    pub fn release_held(&mut self, tracker: &mut dyn PoseTracker) {
        self.hold.release_all(tracker);
    }

    /// The next tick placed, after handing `tracker` the held events up to its time; `None` when there is none
    /// (the latest edge then updates the gate).
    pub fn next_tick(&mut self, tracker: &mut dyn PoseTracker) -> Option<Tick> {
        if let Some(tick) = self.timeline.pop_tick() {
            self.hold.release_until(tick.t_us, tracker);
            return Some(tick);
        }
        self.update_gate(tracker);
        None
    }

    /// Once the ticks of the latest edge are out: the edge opens or closes the gate's pulse, and the gate holds
    /// events from when the next pulse is due. The jitter tolerance early: a tick the timeline places in a gap
    /// lies halfway between its neighbours, so before the schedule when the pulse after the gap comes early (by
    /// up to twice the tolerance before it counts as jittered). Wider, the hold would delay more events to the
    /// tick's own latency.
    fn update_gate(&mut self, tracker: &mut dyn PoseTracker) {
        if let Some(edge) = self.pending_edge.take() {
            self.hold.edge(&edge, tracker);
            let margin = self.timeline.config().jitter_tolerance_us;
            self.hold
                .set_due(self.timeline.next_pulse_due_us().map(|due| due - margin));
        }
    }

    /// The timeline's counters (pulses, missing, gaps, jitter, phase errors).
    pub fn timeline_counters(&self) -> &TimelineCounters {
        self.timeline.counters()
    }

    /// The trigger schedule driven.
    pub fn timeline_config(&self) -> &TimelineConfig {
        self.timeline.config()
    }

    /// Times a trigger outage held more events than the gate keeps, which were then handed over early.
    pub fn hold_overflows(&self) -> u64 {
        self.hold.overflows()
    }

    /// Events held now (after the last tick, at the end of a stream: events no tick followed).
    pub fn held(&self) -> usize {
        self.hold.held()
    }
}

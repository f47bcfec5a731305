//! When each depth frame was exposed, on the event camera's clock: the rising edge of its phase-coded (wide)
//! trigger pulse in `events.raw`, numbered the way the application's replay numbers them
//! (`tracker/app/src/runtime/assembly.rs`): the first wide pulse is frame 0, and each further wide pulse's number
//! is the previous one's plus the number of depth periods between them (rounded, at least 1), so that a missing
//! pulse does not shift the count and the trigger clock's drift never adds up. A frame whose pulse is missing is
//! exposed when the schedule from the latest wide pulse before it says.

use drivers::event::{CdEvent, EventSink, TriggerEdge};
use drivers::recording::TriggerSchedule;

/// What one pass over `events.raw` learns: the first event's time and the trigger pulses on one channel.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct TriggerScan {
    /// Trigger channel scanned.
    channel: u8,
    /// Time of the first CD event or trigger edge, microseconds.
    pub first_event_us: Option<i64>,
    /// Pulses on the channel: rising edge and width, microseconds, in stream order.
    pub pulses: Vec<(i64, i64)>,
    rise: Option<i64>,
}

impl TriggerScan {
    /// A scan of the pulses on `channel`.
    pub fn new(channel: u8) -> Self {
        Self {
            channel,
            ..Self::default()
        }
    }

    fn seen(&mut self, t_us: i64) {
        self.first_event_us.get_or_insert(t_us);
    }
}

impl EventSink for TriggerScan {
    fn cd(&mut self, event: CdEvent) {
        self.seen(event.t_us);
    }

    fn cd_vector(&mut self, t_us: i64, _y: u16, _x_base: u16, _mask: u32, _polarity: bool) {
        self.seen(t_us);
    }

    fn trigger(&mut self, edge: TriggerEdge) {
        self.seen(edge.t_us);
        if edge.channel != self.channel {
            return;
        }
        if edge.rising {
            // A rising edge also ends a pulse whose falling edge was lost: that pulse is forgotten.
            self.rise = Some(edge.t_us);
        } else if let Some(rise) = self.rise.take() {
            self.pulses.push((rise, edge.t_us - rise));
        }
    }
}

/// Depth frame numbers and their exposure times, from the wide pulses of a [`TriggerScan`].
#[derive(Debug, Clone, PartialEq)]
pub struct DepthSchedule {
    /// Each wide pulse's rising edge (microseconds) and its depth frame number, ascending.
    anchors: Vec<(i64, u64)>,
    /// Depth period, microseconds.
    period_us: f64,
    /// Where frame 0 is exposed when the stream has no wide pulse at all (its first event), microseconds.
    fallback_origin_us: i64,
}

/// A depth frame's exposure time, and whether a trigger pulse gave it (rather than the schedule).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Exposure {
    /// Exposure time on the event camera's clock, microseconds.
    pub t_us: i64,
    /// Whether the frame's own phase-coded pulse gave the time (false: the schedule, its pulse missing).
    pub from_pulse: bool,
}

impl DepthSchedule {
    /// The schedule of the wide pulses (width at least `(narrow + wide) / 2`) among `scan`'s pulses.
    pub fn new(scan: &TriggerScan, schedule: &TriggerSchedule) -> Self {
        let threshold = (schedule.narrow_width_us + schedule.wide_width_us) / 2;
        let period_us = f64::from(schedule.ticks_per_depth) * 1e6 / schedule.tick_rate_hz;
        let mut anchors: Vec<(i64, u64)> = Vec::new();
        for &(rise, width) in &scan.pulses {
            if width < threshold {
                continue;
            }
            let n = match anchors.last() {
                None => 0,
                Some(&(at, n)) => {
                    let periods = ((rise - at) as f64 / period_us).round().max(1.0);
                    n + periods as u64
                }
            };
            anchors.push((rise, n));
        }
        Self {
            anchors,
            period_us,
            fallback_origin_us: scan.first_event_us.unwrap_or(0),
        }
    }

    /// Whether the stream had no wide pulse, so that every frame is stamped by the nominal schedule from the
    /// stream's first event.
    pub fn has_no_pulses(&self) -> bool {
        self.anchors.is_empty()
    }

    /// When depth frame `k` was exposed.
    pub fn exposure(&self, k: u64) -> Exposure {
        let i = self.anchors.partition_point(|&(_, n)| n <= k);
        let (at, n) = match i.checked_sub(1).and_then(|i| self.anchors.get(i)) {
            Some(&a) => a,
            None => (self.fallback_origin_us, 0),
        };
        if n == k && i > 0 {
            return Exposure {
                t_us: at,
                from_pulse: true,
            };
        }
        Exposure {
            t_us: at + ((k as f64 - n as f64) * self.period_us).round() as i64,
            from_pulse: false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scan_of(pulses: &[(i64, i64)]) -> TriggerScan {
        let mut s = TriggerScan::new(0);
        s.trigger(TriggerEdge {
            t_us: 1,
            channel: 3,
            rising: true,
        });
        for &(rise, width) in pulses {
            for (t_us, rising) in [(rise, true), (rise + width, false)] {
                s.trigger(TriggerEdge {
                    t_us,
                    channel: 0,
                    rising,
                });
            }
        }
        s
    }

    #[test]
    fn wide_pulses_number_the_frames_and_missing_ones_follow_the_schedule() {
        let sched = TriggerSchedule::default(); // 120 Hz, 4 ticks per depth frame, 100 / 200 us
        let p = 33_333.333;
        let mut pulses = Vec::new();
        for tick in 0..16 {
            let rise = 500 + (f64::from(tick) * p / 4.0).round() as i64;
            // Frame 2's phase-coded pulse (tick 8) is missing: its pulse came narrow.
            let wide = tick % 4 == 0 && tick != 8;
            pulses.push((
                rise + i64::from(tick == 12) * 40,
                if wide { 200 } else { 100 },
            ));
        }
        let scan = scan_of(&pulses);
        assert_eq!(scan.first_event_us, Some(1));
        assert_eq!(scan.pulses.len(), 16);
        let d = DepthSchedule::new(&scan, &sched);
        assert!(!d.has_no_pulses());
        assert_eq!(
            d.exposure(0),
            Exposure {
                t_us: 500,
                from_pulse: true
            }
        );
        assert_eq!(
            d.exposure(1),
            Exposure {
                t_us: 33_833,
                from_pulse: true
            }
        );
        assert_eq!(
            d.exposure(2),
            Exposure {
                t_us: 67_166,
                from_pulse: false
            }
        );
        // Frame 3's pulse came 40 us late: its own edge stamps it.
        assert_eq!(
            d.exposure(3),
            Exposure {
                t_us: 100_540,
                from_pulse: true
            }
        );
        assert_eq!(
            d.exposure(5),
            Exposure {
                t_us: 167_207,
                from_pulse: false
            }
        );
    }

    #[test]
    fn without_wide_pulses_frames_follow_the_schedule_from_the_first_event() {
        let scan = scan_of(&[(500, 100), (8833, 100)]);
        let d = DepthSchedule::new(&scan, &TriggerSchedule::default());
        assert!(d.has_no_pulses());
        assert_eq!(
            d.exposure(0),
            Exposure {
                t_us: 1,
                from_pulse: false
            }
        );
        assert_eq!(
            d.exposure(3),
            Exposure {
                t_us: 100_001,
                from_pulse: false
            }
        );
    }
}

//! The live stream's clock across camera outages. While the camera is away no trigger edge arrives, so no tick
//! would be made and nothing published: the clock then makes the tick pulses itself, on the wall clock, continuing
//! the camera's grid (a phase-coded pulse where the schedule puts one), so the tracker keeps ticking and decides
//! the objects' states from what it has. A camera that comes back starts a new time base (a real one restarts its
//! counter at power-up): its times are moved to continue one period after the last pulse made, so the stream
//! never goes back in time.

use drivers::event::{EventBuffer, TriggerEdge};
use drivers::recording::TriggerSchedule;
use std::time::{Duration, Instant};

/// The clock.
#[derive(Debug)]
pub(super) struct LiveClock {
    schedule: TriggerSchedule,
    period_us: f64,
    /// The latest rising edge on the tick channel delivered, and the latest phase-coded (wide) one.
    last_rise_us: Option<i64>,
    last_wide_rise_us: Option<i64>,
    /// The latest time delivered (events or edges).
    last_us: i64,
    /// While the camera is away: when the latest pulse was made, on the wall clock.
    away_since: Option<Instant>,
    last_made: Option<Instant>,
    /// After the camera came back: the time its stream must continue after, until its first chunk is seen.
    resume_after_us: Option<i64>,
    /// Added to the current camera session's times.
    offset_us: i64,
    /// Pulses made while the camera was away.
    pub(super) pulses_made: u64,
}

impl LiveClock {
    /// A clock for `schedule`'s tick channel and rate.
    pub(super) fn new(schedule: TriggerSchedule) -> Self {
        Self {
            schedule,
            period_us: 1e6 / schedule.tick_rate_hz,
            last_rise_us: None,
            last_wide_rise_us: None,
            last_us: i64::MIN,
            away_since: None,
            last_made: None,
            resume_after_us: None,
            offset_us: 0,
            pulses_made: 0,
        }
    }

    /// Moves a decoded chunk of the current session onto the stream's clock and notes its pulses.
    pub(super) fn map(&mut self, chunk: &mut EventBuffer) {
        if let Some(after) = self.resume_after_us {
            let first = chunk
                .cd
                .first()
                .map(|e| e.t_us)
                .into_iter()
                .chain(chunk.triggers.first().map(|e| e.t_us))
                .min();
            if let Some(first) = first {
                self.resume_after_us = None;
                self.offset_us = (after + self.period_us.round() as i64 - first).max(0);
            }
        }
        if self.offset_us != 0 {
            chunk.cd.iter_mut().for_each(|e| e.t_us += self.offset_us);
            chunk
                .triggers
                .iter_mut()
                .for_each(|e| e.t_us += self.offset_us);
        }
        for e in &chunk.triggers {
            self.note_edge(e, e.rising);
        }
        if let Some(last) = chunk.cd.last() {
            self.last_us = self.last_us.max(last.t_us);
        }
    }

    fn note_edge(&mut self, e: &TriggerEdge, rising: bool) {
        self.last_us = self.last_us.max(e.t_us);
        if e.channel != self.schedule.channel {
            return;
        }
        if rising {
            self.last_rise_us = Some(e.t_us);
        } else if let Some(rise) = self.last_rise_us {
            let wide =
                e.t_us - rise >= (self.schedule.narrow_width_us + self.schedule.wide_width_us) / 2;
            if wide {
                self.last_wide_rise_us = Some(rise);
            }
        }
    }

    /// The camera went away; returns the stream time it was last heard of (ticks after it are made here).
    pub(super) fn camera_lost(&mut self, now: Instant) -> i64 {
        self.away_since = Some(now);
        self.last_made = Some(now);
        self.last_us
    }

    /// The camera is back: its stream continues after everything delivered so far, whose time is returned.
    pub(super) fn camera_back(&mut self) -> i64 {
        self.away_since = None;
        self.resume_after_us = (self.last_us > i64::MIN).then_some(self.last_us);
        self.offset_us = 0;
        self.last_us
    }

    /// While the camera is away, the next tick pulse (rising and falling edge) when its period has passed on the
    /// wall clock since the previous one (call until `None` to catch up); `None` otherwise, or when the camera
    /// never made a pulse to continue from.
    pub(super) fn pulse_due(&mut self, now: Instant) -> Option<[TriggerEdge; 2]> {
        self.away_since?;
        let last = self.last_made?;
        let rise_before = self.last_rise_us?;
        let period = Duration::from_micros(self.period_us.round() as u64);
        if now < last + period {
            return None;
        }
        self.last_made = Some(last + period);
        let rise = rise_before + self.period_us.round() as i64;
        let wide = self.last_wide_rise_us.is_some_and(|w| {
            let ticks = ((rise - w) as f64 / self.period_us).round() as i64;
            ticks % i64::from(self.schedule.ticks_per_depth.max(1)) == 0
        });
        let width = if wide {
            self.schedule.wide_width_us
        } else {
            self.schedule.narrow_width_us
        };
        let channel = self.schedule.channel;
        let edges = [
            TriggerEdge {
                t_us: rise,
                channel,
                rising: true,
            },
            TriggerEdge {
                t_us: rise + width,
                channel,
                rising: false,
            },
        ];
        self.note_edge(&edges[0], true);
        self.note_edge(&edges[1], false);
        self.pulses_made += 1;
        Some(edges)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use drivers::event::CdEvent;

    fn schedule() -> TriggerSchedule {
        TriggerSchedule::default()
    }

    fn pulse(rise: i64, width: i64) -> Vec<TriggerEdge> {
        vec![
            TriggerEdge {
                t_us: rise,
                channel: 0,
                rising: true,
            },
            TriggerEdge {
                t_us: rise + width,
                channel: 0,
                rising: false,
            },
        ]
    }

    #[test]
    fn while_away_pulses_continue_the_grid_with_the_phase_coded_ones_in_place() {
        let s = schedule();
        let period = (1e6 / s.tick_rate_hz).round() as i64;
        let mut clock = LiveClock::new(s);
        let mut chunk = EventBuffer::new();
        // A phase-coded pulse at 0, then three ordinary ones.
        chunk.triggers.extend(pulse(0, s.wide_width_us));
        for k in 1..4 {
            chunk.triggers.extend(pulse(k * period, s.narrow_width_us));
        }
        clock.map(&mut chunk);
        let t0 = Instant::now();
        assert!(
            clock.pulse_due(t0).is_none(),
            "nothing while the camera is there"
        );
        clock.camera_lost(t0);
        assert!(
            clock.pulse_due(t0).is_none(),
            "not before a period has passed"
        );
        let step = Duration::from_micros(period as u64);
        let made: Vec<[TriggerEdge; 2]> = (1..=5)
            .filter_map(|k| clock.pulse_due(t0 + step * k))
            .collect();
        assert_eq!(made.len(), 5);
        let rises: Vec<i64> = made.iter().map(|p| p[0].t_us).collect();
        assert_eq!(rises, (4..9).map(|k| k * period).collect::<Vec<_>>());
        let widths: Vec<i64> = made.iter().map(|p| p[1].t_us - p[0].t_us).collect();
        // Tick 4 and 8 are phase-coded (every fourth from the one at 0).
        assert_eq!(
            widths,
            [
                s.wide_width_us,
                s.narrow_width_us,
                s.narrow_width_us,
                s.narrow_width_us,
                s.wide_width_us
            ]
        );
        assert_eq!(clock.pulses_made, 5);
    }

    #[test]
    fn a_camera_that_comes_back_with_an_earlier_clock_continues_after_the_last_pulse() {
        let s = schedule();
        let period = (1e6 / s.tick_rate_hz).round() as i64;
        let mut clock = LiveClock::new(s);
        let mut chunk = EventBuffer::new();
        chunk.triggers.extend(pulse(1_000_000, s.narrow_width_us));
        clock.map(&mut chunk);
        let t0 = Instant::now();
        clock.camera_lost(t0);
        let made = clock
            .pulse_due(t0 + Duration::from_micros(period as u64))
            .unwrap();
        clock.camera_back();
        // The new session's clock restarted near zero.
        let mut again = EventBuffer::new();
        again.cd.push(CdEvent {
            t_us: 500,
            x: 1,
            y: 1,
            polarity: true,
        });
        again.triggers.extend(pulse(700, s.narrow_width_us));
        clock.map(&mut again);
        let after = made[1].t_us;
        assert_eq!(again.cd[0].t_us, after + period);
        assert_eq!(again.triggers[0].t_us, after + period + 200);
        // A session whose clock is already ahead is left as it is.
        clock.camera_lost(t0);
        clock.camera_back();
        let mut ahead = EventBuffer::new();
        ahead.cd.push(CdEvent {
            t_us: 10_000_000,
            x: 1,
            y: 1,
            polarity: true,
        });
        clock.map(&mut ahead);
        assert_eq!(ahead.cd[0].t_us, 10_000_000);
    }
}

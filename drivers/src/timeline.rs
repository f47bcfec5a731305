//! The trigger timeline: 120 Hz pose ticks and 30 Hz depth exposures placed on the event camera's clock.
//!
//! The trigger MCU sends a 120 Hz pulse train into the event camera's trigger input; the camera records
//! each edge as an `EXT_TRIGGER` word. Every `ticks_per_depth`-th pulse coincides with a depth-camera
//! exposure and is wider (the phase code). From the edges this module produces ticks at the rising edges,
//! marks the depth-exposure ticks with their depth frame number (counting 30 Hz pulses from the first one
//! seen), and detects, counts and bridges missing, extra and jittered pulses (DESIGN section 4).

use crate::event::TriggerEdge;
use std::collections::VecDeque;

/// Parameters of the trigger schedule.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimelineConfig {
    /// Trigger input channel carrying the pulse train.
    pub channel: u8,
    /// Nominal tick rate, Hz (pulses per second on `channel`).
    pub tick_rate_hz: f64,
    /// Ticks per depth exposure (4 for 120 Hz / 30 Hz).
    pub ticks_per_depth: u32,
    /// Width of an ordinary pulse, microseconds.
    pub narrow_width_us: i64,
    /// Width of a pulse that coincides with a depth exposure, microseconds.
    pub wide_width_us: i64,
    /// Largest deviation from the period estimate that is not counted as jitter, microseconds.
    pub jitter_tolerance_us: i64,
    /// Most missing pulses in a row that are bridged with synthesised ticks. A longer gap (the trigger stopped, or
    /// the event clock jumped in a damaged stream) is counted as a gap and not filled: ticks resume at the next
    /// pulse, with the tick numbers the gap's length gives, so the depth schedule holds.
    pub max_bridged_ticks: u64,
}

impl Default for TimelineConfig {
    fn default() -> Self {
        Self {
            channel: 0,
            tick_rate_hz: 120.0,
            ticks_per_depth: 4,
            narrow_width_us: 100,
            wide_width_us: 200,
            jitter_tolerance_us: 50,
            max_bridged_ticks: 120,
        }
    }
}

impl TimelineConfig {
    /// Nominal tick period, microseconds.
    pub fn period_us(&self) -> f64 {
        1e6 / self.tick_rate_hz
    }
}

/// One pose tick on the event camera's clock.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Tick {
    /// Tick number, 0 at the first pulse seen; consecutive even across bridged gaps.
    pub index: u64,
    /// Time of the tick's rising edge (or the interpolated time of a bridged tick), microseconds.
    pub t_us: i64,
    /// For a depth-exposure tick, the depth frame number (0 = first 30 Hz pulse seen); `None` otherwise
    /// and for ticks before the first phase-coded pulse.
    pub depth_frame: Option<u64>,
    /// `true` when no pulse was seen and the tick was synthesised from the period.
    pub synthesized: bool,
}

/// What the timeline detected; every irregular edge or pulse is counted here.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct TimelineCounters {
    /// Pulses accepted as ticks.
    pub pulses: u64,
    /// Ticks synthesised where pulses were missing.
    pub missing: u64,
    /// Gaps between pulses longer than [`TimelineConfig::max_bridged_ticks`]: not bridged.
    pub gaps: u64,
    /// Ticks the gaps left out (not synthesised).
    pub unbridged: u64,
    /// Pulses dropped because they came far too early (less than half a period after a tick).
    pub extra: u64,
    /// Accepted pulses that deviated from the period estimate by more than the tolerance.
    pub jittered: u64,
    /// Phase-coded pulses that were not where the schedule put them (the phase was re-locked).
    pub phase_errors: u64,
    /// Pulses at a depth-exposure tick that were not wide (depth frame assigned from the schedule).
    pub missing_phase_code: u64,
    /// Rising edges without a falling edge before the next rising edge.
    pub unpaired_rising: u64,
    /// Falling edges without a preceding rising edge.
    pub unpaired_falling: u64,
    /// Edges on other trigger channels (ignored).
    pub other_channel: u64,
}

impl TimelineCounters {
    /// Sum of the irregularity counters (everything except `pulses` and `other_channel`).
    pub fn irregularities(&self) -> u64 {
        self.missing
            + self.gaps
            + self.extra
            + self.jittered
            + self.phase_errors
            + self.missing_phase_code
            + self.unpaired_rising
            + self.unpaired_falling
    }
}

/// Streaming trigger timeline: push edges in time order, pop ticks.
#[derive(Debug, Clone)]
pub struct TriggerTimeline {
    config: TimelineConfig,
    period_us: f64,
    pending_rise: Option<i64>,
    last_tick: Option<(u64, i64)>,
    /// `(tick index, depth frame)` of the last depth-exposure tick; sets the phase.
    depth_anchor: Option<(u64, u64)>,
    ticks: VecDeque<Tick>,
    counters: TimelineCounters,
}

impl TriggerTimeline {
    /// An empty timeline.
    pub fn new(config: TimelineConfig) -> Self {
        Self {
            period_us: config.period_us(),
            config,
            pending_rise: None,
            last_tick: None,
            depth_anchor: None,
            ticks: VecDeque::with_capacity(16),
            counters: TimelineCounters::default(),
        }
    }

    /// The configuration.
    pub fn config(&self) -> &TimelineConfig {
        &self.config
    }

    /// Counters so far.
    pub fn counters(&self) -> &TimelineCounters {
        &self.counters
    }

    /// Current estimate of the tick period on the event camera's clock, microseconds.
    pub fn period_us(&self) -> f64 {
        self.period_us
    }

    /// When the next pulse's rising edge is due on the event camera's clock, microseconds: one period estimate
    /// after the open pulse's rising edge, else after the latest tick. `None` before the first pulse.
    pub fn next_pulse_due_us(&self) -> Option<i64> {
        let last = self.pending_rise.or(self.last_tick.map(|(_, t)| t))?;
        Some(last + self.period_us.round() as i64)
    }

    /// Feeds one edge. A tick becomes available once its pulse's falling edge (or the next rising edge) is seen.
    pub fn push(&mut self, edge: TriggerEdge) {
        if edge.channel != self.config.channel {
            self.counters.other_channel += 1;
            return;
        }
        if edge.rising {
            if let Some(rise) = self.pending_rise.replace(edge.t_us) {
                self.counters.unpaired_rising += 1;
                self.pulse(rise, None);
            }
        } else {
            match self.pending_rise.take() {
                Some(rise) => self.pulse(rise, Some(edge.t_us - rise)),
                None => self.counters.unpaired_falling += 1,
            }
        }
    }

    /// Ends the edge stream: a last rising edge without its falling edge still makes a tick.
    pub fn finish(&mut self) {
        if let Some(rise) = self.pending_rise.take() {
            self.counters.unpaired_rising += 1;
            self.pulse(rise, None);
        }
    }

    /// The next tick, in order.
    pub fn pop_tick(&mut self) -> Option<Tick> {
        self.ticks.pop_front()
    }

    /// The tick a time falls in: the index of the latest tick at or before `t_us`, extrapolated with the period
    /// estimate from the last tick (`None` before the first tick).
    pub fn tick_index_at(&self, t_us: i64) -> Option<u64> {
        let (index, t) = self.last_tick?;
        let steps = ((t_us - t) as f64 / self.period_us).floor() as i64;
        u64::try_from(index as i64 + steps).ok()
    }

    fn pulse(&mut self, t: i64, width: Option<i64>) {
        let threshold = (self.config.narrow_width_us + self.config.wide_width_us) / 2;
        let wide = width.map(|w| w >= threshold);
        let index = match self.last_tick {
            None => 0,
            Some((last_index, last_t)) => {
                let dt = (t - last_t) as f64;
                let k = (dt / self.period_us).round();
                if k < 1.0 {
                    self.counters.extra += 1;
                    return;
                }
                let k = k as u64;
                let residual = dt - k as f64 * self.period_us;
                if residual.abs() > self.config.jitter_tolerance_us as f64 {
                    self.counters.jittered += 1;
                } else if k == 1 {
                    // Track the MCU's clock as seen by the camera's, within 1 % of nominal.
                    let nominal = self.config.period_us();
                    self.period_us =
                        (self.period_us + 0.02 * residual).clamp(nominal * 0.99, nominal * 1.01);
                }
                if k - 1 > self.config.max_bridged_ticks {
                    self.counters.gaps += 1;
                    self.counters.unbridged += k - 1;
                } else {
                    for i in 1..k {
                        let ti = last_t + (dt * i as f64 / k as f64).round() as i64;
                        self.counters.missing += 1;
                        self.emit(last_index + i, ti, None, true);
                    }
                }
                last_index + k
            }
        };
        self.counters.pulses += 1;
        self.emit(index, t, wide, false);
    }

    fn emit(&mut self, index: u64, t: i64, wide: Option<bool>, synthesized: bool) {
        let per = u64::from(self.config.ticks_per_depth.max(1));
        let scheduled = self.depth_anchor.and_then(|(ai, an)| {
            let d = index.checked_sub(ai)?;
            (d % per == 0).then_some(an + d / per)
        });
        let depth_frame = match (wide, scheduled) {
            (Some(true), Some(n)) => Some(n),
            (Some(true), None) => {
                // First phase-coded pulse, or one off the schedule: (re-)lock the phase here.
                let n = match self.depth_anchor {
                    None => 0,
                    Some((ai, an)) => {
                        self.counters.phase_errors += 1;
                        an + ((index - ai) as f64 / per as f64).round().max(1.0) as u64
                    }
                };
                Some(n)
            }
            (Some(false), Some(n)) => {
                self.counters.missing_phase_code += 1;
                Some(n)
            }
            (None, s) => s,
            (Some(false), None) => None,
        };
        if let Some(n) = depth_frame {
            self.depth_anchor = Some((index, n));
        }
        self.last_tick = Some((index, t));
        self.ticks.push_back(Tick {
            index,
            t_us: t,
            depth_frame,
            synthesized,
        });
    }
}

/// Adapts an iterator of trigger edges into an iterator of ticks.
pub struct TickIter<I> {
    edges: I,
    timeline: TriggerTimeline,
    finished: bool,
}

impl<I: Iterator<Item = TriggerEdge>> TickIter<I> {
    /// Ticks from `edges` under `config`.
    pub fn new(config: TimelineConfig, edges: I) -> Self {
        Self {
            edges,
            timeline: TriggerTimeline::new(config),
            finished: false,
        }
    }

    /// The timeline (its counters are final once the iterator is exhausted).
    pub fn timeline(&self) -> &TriggerTimeline {
        &self.timeline
    }
}

impl<I: Iterator<Item = TriggerEdge>> Iterator for TickIter<I> {
    type Item = Tick;

    fn next(&mut self) -> Option<Tick> {
        loop {
            if let Some(t) = self.timeline.pop_tick() {
                return Some(t);
            }
            if self.finished {
                return None;
            }
            match self.edges.next() {
                Some(e) => self.timeline.push(e),
                None => {
                    self.timeline.finish();
                    self.finished = true;
                }
            }
        }
    }
}

/// The edges an ideal trigger MCU produces: `count` pulses from `t0_us` on `config.channel`, every
/// `ticks_per_depth`-th one (starting with the first) wide. Times are rounded to whole microseconds from
/// the exact period, so they never drift.
pub fn ideal_edges(config: &TimelineConfig, t0_us: i64, count: u64) -> Vec<TriggerEdge> {
    let per = u64::from(config.ticks_per_depth.max(1));
    let mut edges = Vec::with_capacity(count as usize * 2);
    for i in 0..count {
        let t = t0_us + (i as f64 * config.period_us()).round() as i64;
        let w = if i % per == 0 {
            config.wide_width_us
        } else {
            config.narrow_width_us
        };
        edges.push(TriggerEdge {
            t_us: t,
            channel: config.channel,
            rising: true,
        });
        edges.push(TriggerEdge {
            t_us: t + w,
            channel: config.channel,
            rising: false,
        });
    }
    edges
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(edges: Vec<TriggerEdge>) -> (Vec<Tick>, TimelineCounters) {
        let mut it = TickIter::new(TimelineConfig::default(), edges.into_iter());
        let ticks: Vec<Tick> = it.by_ref().collect();
        (ticks, *it.timeline().counters())
    }

    #[test]
    fn ideal_schedule_gives_ticks_and_depth_phases() {
        let cfg = TimelineConfig::default();
        let (ticks, c) = run(ideal_edges(&cfg, 1000, 120 * 60));
        assert_eq!(ticks.len(), 7200);
        assert_eq!(c.irregularities(), 0, "{c:?}");
        for (i, t) in ticks.iter().enumerate() {
            assert_eq!(t.index, i as u64);
            assert_eq!(t.depth_frame, (i % 4 == 0).then_some(i as u64 / 4));
            assert!(!t.synthesized);
        }
        // One minute later the tick is still exactly on the 120 Hz grid (no accumulated drift).
        assert_eq!(
            ticks[7199].t_us,
            1000 + (7199.0 * 1e6 / 120.0f64).round() as i64
        );
    }

    #[test]
    fn missing_pulses_are_bridged_and_counted() {
        let cfg = TimelineConfig::default();
        let mut edges = ideal_edges(&cfg, 0, 20);
        // Drop pulses 5, 6 and 8 (8 is a depth exposure).
        edges.retain(|e| {
            let i = (e.t_us as f64 / cfg.period_us()).round() as i64;
            ![5, 6, 8].contains(&i)
        });
        let (ticks, c) = run(edges);
        assert_eq!(ticks.len(), 20);
        assert_eq!(c.missing, 3);
        let synth: Vec<u64> = ticks
            .iter()
            .filter(|t| t.synthesized)
            .map(|t| t.index)
            .collect();
        assert_eq!(synth, vec![5, 6, 8]);
        assert_eq!(ticks[8].depth_frame, Some(2));
        assert_eq!(ticks[12].depth_frame, Some(3));
        assert!((ticks[5].t_us - (5.0 * cfg.period_us()) as i64).abs() <= 1);
    }

    #[test]
    fn a_gap_longer_than_the_bridge_limit_is_counted_not_filled() {
        let cfg = TimelineConfig {
            max_bridged_ticks: 10,
            ..TimelineConfig::default()
        };
        let mut edges = ideal_edges(&cfg, 0, 60);
        // Pulses 5..=15 missing (11 in a row: over the limit), then 30..=39 (10: bridged).
        edges.retain(|e| {
            let i = (e.t_us as f64 / cfg.period_us()).round() as i64;
            !(5..=15).contains(&i) && !(30..=39).contains(&i)
        });
        let mut it = TickIter::new(cfg, edges.into_iter());
        let ticks: Vec<Tick> = it.by_ref().collect();
        let c = *it.timeline().counters();
        assert_eq!((c.gaps, c.unbridged, c.missing), (1, 11, 10));
        assert_eq!(ticks.len(), 60 - 11);
        let indices: Vec<u64> = ticks.iter().map(|t| t.index).collect();
        assert_eq!(&indices[..6], &[0, 1, 2, 3, 4, 16]);
        // Numbering continues across the gap, so depth frames stay on their pulses.
        let after = ticks.iter().find(|t| t.index == 16).unwrap();
        assert_eq!(after.depth_frame, Some(4));
        assert!(
            ticks
                .iter()
                .filter(|t| t.synthesized)
                .all(|t| (30..=39).contains(&t.index))
        );
        assert!(c.irregularities() >= 11);
    }

    #[test]
    fn extra_and_jittered_pulses_are_counted() {
        let cfg = TimelineConfig::default();
        let mut edges = ideal_edges(&cfg, 0, 12);
        // A glitch pulse 1 ms after pulse 2, and pulse 6 late by 300 us.
        let t2 = (2.0 * cfg.period_us()).round() as i64;
        edges.push(TriggerEdge {
            t_us: t2 + 1000,
            channel: 0,
            rising: true,
        });
        edges.push(TriggerEdge {
            t_us: t2 + 1100,
            channel: 0,
            rising: false,
        });
        for e in edges.iter_mut() {
            if (e.t_us as f64 / cfg.period_us()).round() as i64 == 6 {
                e.t_us += 300;
            }
        }
        edges.sort_by_key(|e| e.t_us);
        let (ticks, c) = run(edges);
        assert_eq!(ticks.len(), 12);
        assert_eq!(c.extra, 1);
        assert_eq!(c.jittered, 2, "late pulse 6 and the early one after it");
        assert_eq!(ticks[8].depth_frame, Some(2));
    }

    #[test]
    fn phase_is_learnt_from_the_first_wide_pulse() {
        let cfg = TimelineConfig::default();
        // Start the recording two ticks before a depth exposure.
        let edges: Vec<TriggerEdge> = ideal_edges(&cfg, 0, 20)
            .into_iter()
            .filter(|e| e.t_us >= (2.0 * cfg.period_us()) as i64 - 1)
            .collect();
        let (ticks, c) = run(edges);
        assert_eq!(ticks[0].depth_frame, None);
        assert_eq!(ticks[1].depth_frame, None);
        assert_eq!(ticks[2].depth_frame, Some(0));
        assert_eq!(ticks[6].depth_frame, Some(1));
        assert_eq!(c.irregularities(), 0);
    }

    #[test]
    fn lost_falling_edges_and_stray_channels_do_not_break_the_timeline() {
        let cfg = TimelineConfig::default();
        let mut edges = ideal_edges(&cfg, 0, 8);
        edges.remove(3); // falling edge of pulse 1
        edges.insert(
            0,
            TriggerEdge {
                t_us: 0,
                channel: 3,
                rising: true,
            },
        );
        edges.insert(
            0,
            TriggerEdge {
                t_us: 0,
                channel: 0,
                rising: false,
            },
        );
        let (ticks, c) = run(edges);
        assert_eq!(ticks.len(), 8);
        assert_eq!(c.unpaired_rising, 1);
        assert_eq!(c.unpaired_falling, 1);
        assert_eq!(c.other_channel, 1);
        assert_eq!(ticks[4].depth_frame, Some(1));
    }
}

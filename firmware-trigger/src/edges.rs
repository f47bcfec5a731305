//! The ideal edge sequence of a run, in timer ticks since start: what the two timers emit.
//!
//! Used by the host tests (exactness, drift), by the QEMU variant (which replays it from
//! SysTick) and by the tracker bridge test (which encodes it as EVT3 trigger words).

use crate::plan::{EVENT_PER_DEPTH, Line, TimerPlan, is_coded};

/// One edge on one output line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Edge {
    /// Time of the edge in timer ticks since the run started (tick 0 = first rising edges).
    pub t_ticks: u64,
    /// Which output.
    pub line: Line,
    /// Rising (pulse start) or falling (pulse end).
    pub rising: bool,
    /// Index of the pulse on its line, counting from 0 at start.
    pub index: u64,
    /// For event pulses: true for the phase-coded (wider) pulse that coincides with a depth
    /// pulse. Always true for depth pulses.
    pub coded: bool,
}

/// Next pending edge of one line.
#[derive(Clone, Copy, Debug)]
struct Pending {
    t_ticks: u64,
    rising: bool,
    index: u64,
}

/// Iterator over a run's edges in time order, without end. Edges at the same tick are ordered
/// depth before event (every depth rising edge shares its tick with an event rising edge).
#[derive(Clone, Debug)]
pub struct EdgeSchedule {
    plan: TimerPlan,
    depth: Pending,
    event: Pending,
}

impl EdgeSchedule {
    /// The edges of a run of `plan` starting at tick 0.
    pub fn new(plan: &TimerPlan) -> Self {
        let first = Pending {
            t_ticks: 0,
            rising: true,
            index: 0,
        };
        Self {
            plan: *plan,
            depth: first,
            event: first,
        }
    }

    /// Time of the next edge without consuming it, ticks.
    pub fn peek_time(&self) -> u64 {
        self.depth.t_ticks.min(self.event.t_ticks)
    }

    fn advance(plan: &TimerPlan, line: Line, p: Pending) -> Pending {
        let (period, width) = match line {
            Line::Depth => (
                u64::from(plan.depth_period_ticks()),
                u64::from(plan.depth_width_ticks()),
            ),
            Line::Event => (
                u64::from(plan.event_period_ticks()),
                u64::from(plan.event_width_for(p.index)),
            ),
        };
        if p.rising {
            Pending {
                t_ticks: p.t_ticks.saturating_add(width),
                rising: false,
                index: p.index,
            }
        } else {
            let index = p.index.saturating_add(1);
            Pending {
                t_ticks: index.saturating_mul(period),
                rising: true,
                index,
            }
        }
    }
}

impl Iterator for EdgeSchedule {
    type Item = Edge;

    fn next(&mut self) -> Option<Edge> {
        let line = if self.depth.t_ticks <= self.event.t_ticks {
            Line::Depth
        } else {
            Line::Event
        };
        let pending = match line {
            Line::Depth => &mut self.depth,
            Line::Event => &mut self.event,
        };
        let p = *pending;
        *pending = Self::advance(&self.plan, line, p);
        Some(Edge {
            t_ticks: p.t_ticks,
            line,
            rising: p.rising,
            index: p.index,
            coded: line == Line::Depth || is_coded(p.index),
        })
    }
}

/// Converts a tick time at `from_hz` to the nearest cycle at `to_hz` (half rounds up).
/// Exact integer arithmetic on absolute times, so rounding never accumulates: a period
/// converted this way is within one `to_hz` cycle of ideal however long the run.
pub fn rescale(t: u64, from_hz: u32, to_hz: u32) -> u64 {
    if from_hz == 0 {
        return 0;
    }
    let from = u128::from(from_hz);
    let scaled = (u128::from(t) * u128::from(to_hz) + from / 2) / from;
    u64::try_from(scaled).unwrap_or(u64::MAX)
}

/// Index of the depth pulse that event pulse `event_index` coincides with, if it does.
pub fn depth_index_of_event(event_index: u64) -> Option<u64> {
    is_coded(event_index).then(|| event_index / u64::from(EVENT_PER_DEPTH))
}

//! Timer plan: prescaler, reload and compare values that make the depth and event pulse trains
//! exact at a given timer clock, or a refusal saying why they cannot be exact.
//!
//! The hardware model (DESIGN section 8): one prescaler value shared by a 32-bit master timer
//! (depth camera, `rate` Hz) and a 16-bit slave timer (event camera, `EVENT_PER_DEPTH x rate` Hz),
//! both counting up from 0 to their reload value and emitting a pulse (PWM mode 1) that is high
//! from counter 0 to the compare value. Periods are `reload + 1` ticks of `clock / (prescaler + 1)`.

use core::fmt;

/// Event (120 Hz) pulses per depth (30 Hz) pulse: the exact ratio the rig relies on.
pub const EVENT_PER_DEPTH: u32 = 4;

/// Minimum pulse the RealSense D435i sync input accepts, in nanoseconds (it wants pulses *over*
/// 100 us; the plan requires the realised width to be strictly longer).
pub const DEPTH_MIN_PULSE_NS: u64 = 100_000;

/// Minimum pulse the EVK4 trigger input needs, in nanoseconds (at least 500 ns).
pub const EVENT_MIN_PULSE_NS: u64 = 500;

/// Largest divider of a 16-bit prescaler register (`PSC + 1`).
const MAX_DIVIDER: u64 = 1 << 16;

/// Largest period, in ticks, of the 16-bit slave timer (`ARR + 1`).
const MAX_EVENT_PERIOD: u64 = 1 << 16;

/// Requested pulse widths in nanoseconds. The plan rounds each up to whole timer ticks (a pulse
/// is never shorter than requested, since the cameras specify minimums).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PulseWidths {
    /// Width of every depth (30 Hz) pulse, ns. Must realise to more than 100 us.
    pub depth_ns: u32,
    /// Width of a plain event (120 Hz) pulse, ns. At least 500 ns.
    pub event_ns: u32,
    /// Width of the phase-coded event pulse (the one that coincides with a depth pulse), ns.
    /// At least 1.5 x the plain width so the tracker can tell them apart.
    pub event_coded_ns: u32,
}

impl Default for PulseWidths {
    /// 1 ms depth pulses, 100 us plain and 200 us phase-coded event pulses.
    fn default() -> Self {
        Self {
            depth_ns: 1_000_000,
            event_ns: 100_000,
            event_coded_ns: 200_000,
        }
    }
}

/// Which of the two pulse trains a value refers to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Line {
    /// The depth-camera train (30 Hz by default), from the 32-bit master timer.
    Depth,
    /// The event-camera train (4 x the depth rate), from the 16-bit slave timer.
    Event,
}

impl fmt::Display for Line {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Line::Depth => "depth",
            Line::Event => "event",
        })
    }
}

/// Which pulse a width error is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pulse {
    /// Every depth pulse.
    Depth,
    /// A plain event pulse.
    Event,
    /// The phase-coded (wider) event pulse.
    EventCoded,
}

impl fmt::Display for Pulse {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Pulse::Depth => "depth pulse",
            Pulse::Event => "event pulse",
            Pulse::EventCoded => "phase-coded event pulse",
        })
    }
}

/// Why no exact plan exists for a clock, rate and set of widths.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlanError {
    /// The timer clock or the depth rate is zero.
    Zero,
    /// The clock is not a whole multiple of the depth rate: the depth train cannot be exact.
    InexactDepthRate {
        /// Timer clock, Hz.
        clock_hz: u32,
        /// Requested depth rate, Hz.
        depth_hz: u32,
    },
    /// The depth rate is exact but the clock is not a whole multiple of 4 x the depth rate:
    /// the exact 4:1 ratio (and so phase lock) cannot be met.
    InexactRatio {
        /// Timer clock, Hz.
        clock_hz: u32,
        /// Requested depth rate, Hz.
        depth_hz: u32,
    },
    /// No 16-bit prescaler divides the event period into a count that fits the 16-bit slave.
    NoPrescaler {
        /// Event period in timer-clock cycles.
        event_period_cycles: u64,
    },
    /// A width rounds to a pulse at or below the camera's minimum.
    WidthTooShort {
        /// Which pulse.
        pulse: Pulse,
        /// Realised width, ns.
        width_ns: u64,
        /// Minimum the camera needs, ns (the width must exceed it for depth, reach it for events).
        min_ns: u64,
    },
    /// A width leaves no low time in its period (the pulse would never fall).
    WidthTooLong {
        /// Which pulse.
        pulse: Pulse,
        /// Width in timer ticks.
        width_ticks: u64,
        /// Period of that train in timer ticks.
        period_ticks: u64,
    },
    /// The phase-coded width is not at least 1.5 x the plain event width.
    CodeNotDistinct {
        /// Plain event width, ticks.
        event_ticks: u64,
        /// Phase-coded width, ticks.
        coded_ticks: u64,
    },
}

impl fmt::Display for PlanError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            PlanError::Zero => f.write_str("timer clock and depth rate must be non-zero"),
            PlanError::InexactDepthRate { clock_hz, depth_hz } => write!(
                f,
                "{clock_hz} Hz timer clock is not a whole multiple of {depth_hz} Hz: depth pulses cannot be exact"
            ),
            PlanError::InexactRatio { clock_hz, depth_hz } => write!(
                f,
                "{clock_hz} Hz timer clock is not a whole multiple of {} Hz: the exact {EVENT_PER_DEPTH}:1 ratio cannot be met",
                u64::from(depth_hz) * u64::from(EVENT_PER_DEPTH)
            ),
            PlanError::NoPrescaler {
                event_period_cycles,
            } => write!(
                f,
                "no 16-bit prescaler fits an event period of {event_period_cycles} clock cycles into a 16-bit timer"
            ),
            PlanError::WidthTooShort {
                pulse,
                width_ns,
                min_ns,
            } => write!(
                f,
                "{pulse} of {width_ns} ns is too short (camera needs {min_ns} ns)"
            ),
            PlanError::WidthTooLong {
                pulse,
                width_ticks,
                period_ticks,
            } => write!(
                f,
                "{pulse} of {width_ticks} ticks leaves no low time in a {period_ticks}-tick period"
            ),
            PlanError::CodeNotDistinct {
                event_ticks,
                coded_ticks,
            } => write!(
                f,
                "phase-coded pulse ({coded_ticks} ticks) must be at least 1.5 x the plain pulse ({event_ticks} ticks)"
            ),
        }
    }
}

/// Register values for the two timers, all exact at the timer clock they were planned for.
///
/// Invariants (checked by [`TimerPlan::new`]): `depth_period_ticks == 4 * event_period_ticks`;
/// `tick_hz * 1 == event_period_ticks * event_hz` exactly; every width is at least one tick and
/// shorter than its period; the coded width is at least 1.5 x the plain event width.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TimerPlan {
    widths: PulseWidths,
    clock_hz: u32,
    depth_hz: u32,
    prescaler: u16,
    event_reload: u16,
    depth_width: u32,
    event_width: u16,
    event_coded_width: u16,
}

impl TimerPlan {
    /// Plans both timers for a timer clock (`clock_hz`, the clock feeding the prescalers, e.g.
    /// 84 MHz on the STM32F401's APB1 timers) and a depth rate (`depth_hz`, e.g. 30); the event
    /// rate is `EVENT_PER_DEPTH x depth_hz`. Picks the smallest prescaler (finest tick) that
    /// keeps the event period within 16 bits. Refuses any clock at which the rates or the
    /// exact 4:1 ratio cannot be met, and widths the cameras would not accept.
    pub fn new(clock_hz: u32, depth_hz: u32, widths: PulseWidths) -> Result<Self, PlanError> {
        if clock_hz == 0 || depth_hz == 0 {
            return Err(PlanError::Zero);
        }
        let clock = u64::from(clock_hz);
        let depth = u64::from(depth_hz);
        if clock % depth != 0 {
            return Err(PlanError::InexactDepthRate { clock_hz, depth_hz });
        }
        let event_hz = depth * u64::from(EVENT_PER_DEPTH);
        if clock % event_hz != 0 {
            return Err(PlanError::InexactRatio { clock_hz, depth_hz });
        }
        let event_period_cycles = clock / event_hz;
        // Smallest divider d (<= 2^16) of the event period with period / d <= 2^16.
        let min_divider = event_period_cycles.div_ceil(MAX_EVENT_PERIOD).max(1);
        let divider = (min_divider..=MAX_DIVIDER.min(event_period_cycles))
            .find(|d| event_period_cycles % d == 0)
            .ok_or(PlanError::NoPrescaler {
                event_period_cycles,
            })?;
        let event_period = event_period_cycles / divider;
        let tick_hz = clock / divider;
        let depth_period = event_period * u64::from(EVENT_PER_DEPTH);

        // Products of two 32-bit quantities and 1e9 need 128 bits to be safe.
        let ticks = |ns: u32| (u64::from(ns) * tick_hz).div_ceil(1_000_000_000);
        let ns_of = |ticks: u64| {
            u64::try_from(u128::from(ticks) * 1_000_000_000 / u128::from(tick_hz))
                .unwrap_or(u64::MAX)
        };
        let depth_width = ticks(widths.depth_ns);
        let event_width = ticks(widths.event_ns);
        let coded_width = ticks(widths.event_coded_ns);

        for (pulse, width, min_ns, strictly_more) in [
            (Pulse::Depth, depth_width, DEPTH_MIN_PULSE_NS, true),
            (Pulse::Event, event_width, EVENT_MIN_PULSE_NS, false),
            (Pulse::EventCoded, coded_width, EVENT_MIN_PULSE_NS, false),
        ] {
            let width_ns = ns_of(width);
            let exact_ns = u128::from(width) * 1_000_000_000;
            let min_exact = u128::from(min_ns) * u128::from(tick_hz);
            let too_short = if strictly_more {
                exact_ns <= min_exact
            } else {
                exact_ns < min_exact
            };
            if width == 0 || too_short {
                return Err(PlanError::WidthTooShort {
                    pulse,
                    width_ns,
                    min_ns,
                });
            }
        }
        for (pulse, width, period) in [
            (Pulse::Depth, depth_width, depth_period),
            (Pulse::Event, event_width, event_period),
            (Pulse::EventCoded, coded_width, event_period),
        ] {
            if width >= period {
                return Err(PlanError::WidthTooLong {
                    pulse,
                    width_ticks: width,
                    period_ticks: period,
                });
            }
        }
        if 2 * coded_width < 3 * event_width {
            return Err(PlanError::CodeNotDistinct {
                event_ticks: event_width,
                coded_ticks: coded_width,
            });
        }

        // The range checks above bound every value; the conversions cannot fail, but stay
        // checked rather than truncating.
        let narrow = |v: u64| {
            u16::try_from(v).map_err(|_| PlanError::NoPrescaler {
                event_period_cycles,
            })
        };
        Ok(Self {
            widths,
            clock_hz,
            depth_hz,
            prescaler: narrow(divider - 1)?,
            event_reload: narrow(event_period - 1)?,
            depth_width: u32::try_from(depth_width).map_err(|_| PlanError::WidthTooLong {
                pulse: Pulse::Depth,
                width_ticks: depth_width,
                period_ticks: depth_period,
            })?,
            event_width: narrow(event_width)?,
            event_coded_width: narrow(coded_width)?,
        })
    }

    /// Timer clock this plan was made for, Hz.
    pub fn clock_hz(&self) -> u32 {
        self.clock_hz
    }

    /// The widths this plan was made from, as requested (ns).
    pub fn widths(&self) -> PulseWidths {
        self.widths
    }

    /// Depth (master) pulse rate, Hz.
    pub fn depth_hz(&self) -> u32 {
        self.depth_hz
    }

    /// Event (slave) pulse rate, Hz: exactly `EVENT_PER_DEPTH x depth_hz`.
    pub fn event_hz(&self) -> u32 {
        self.depth_hz * EVENT_PER_DEPTH
    }

    /// Value for both timers' prescaler registers (`PSC`): the clock is divided by `PSC + 1`.
    pub fn prescaler(&self) -> u16 {
        self.prescaler
    }

    /// Counter tick rate, Hz: `clock_hz / (prescaler + 1)`, exact.
    pub fn tick_hz(&self) -> u32 {
        self.clock_hz / (u32::from(self.prescaler) + 1)
    }

    /// Auto-reload value of the 16-bit event (slave) timer (`ARR`); period is `ARR + 1` ticks.
    pub fn event_reload(&self) -> u16 {
        self.event_reload
    }

    /// Auto-reload value of the 32-bit depth (master) timer (`ARR`); period is `ARR + 1` ticks.
    pub fn depth_reload(&self) -> u32 {
        self.depth_period_ticks() - 1
    }

    /// Event period in ticks.
    pub fn event_period_ticks(&self) -> u32 {
        u32::from(self.event_reload) + 1
    }

    /// Depth period in ticks: exactly `EVENT_PER_DEPTH x event_period_ticks`.
    pub fn depth_period_ticks(&self) -> u32 {
        self.event_period_ticks() * EVENT_PER_DEPTH
    }

    /// Depth pulse width in ticks (master compare value `CCR`).
    pub fn depth_width_ticks(&self) -> u32 {
        self.depth_width
    }

    /// Plain event pulse width in ticks.
    pub fn event_width_ticks(&self) -> u16 {
        self.event_width
    }

    /// Phase-coded event pulse width in ticks.
    pub fn event_coded_width_ticks(&self) -> u16 {
        self.event_coded_width
    }

    /// Width in ticks (slave compare value `CCR`) of event pulse `index` (0 = the first pulse
    /// after start). Pulses whose index is a multiple of `EVENT_PER_DEPTH` coincide with a
    /// depth pulse and carry the phase code (the wider width).
    pub fn event_width_for(&self, index: u64) -> u16 {
        if is_coded(index) {
            self.event_coded_width
        } else {
            self.event_width
        }
    }

    /// Converts a tick count to nanoseconds (rounded down).
    pub fn ticks_to_ns(&self, ticks: u64) -> u64 {
        u64::try_from(u128::from(ticks) * 1_000_000_000 / u128::from(self.tick_hz()))
            .unwrap_or(u64::MAX)
    }
}

/// True when event pulse `index` coincides with a depth pulse (and so carries the phase code).
pub fn is_coded(index: u64) -> bool {
    index.is_multiple_of(u64::from(EVENT_PER_DEPTH))
}

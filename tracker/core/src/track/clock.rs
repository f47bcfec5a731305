//! The tick clock: the trigger timeline's rate as the tracker and its drivers see it. Every period, half period
//! and first-tick step derives from it, so a rig triggered at another rate than 120 Hz is tracked as consistently.

use drivers::timeline::TimelineConfig;

/// The nominal rate of the ticks (the trigger's pose pulses), from the timeline's configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TickClock {
    /// Ticks per second, Hz (120 on the reference rig).
    pub tick_rate_hz: f64,
}

impl Default for TickClock {
    fn default() -> Self {
        Self::of(&TimelineConfig::default())
    }
}

impl TickClock {
    /// The clock of a trigger timeline.
    pub fn of(timeline: &TimelineConfig) -> Self {
        Self {
            tick_rate_hz: timeline.tick_rate_hz,
        }
    }

    /// The nominal period, seconds.
    pub fn period_s(&self) -> f64 {
        1.0 / self.tick_rate_hz
    }

    /// The nominal period, microseconds.
    pub fn period_us(&self) -> f64 {
        1e6 / self.tick_rate_hz
    }

    /// The nominal period to the nearest microsecond (8333 at 120 Hz).
    pub fn whole_period_us(&self) -> i64 {
        self.period_us().round() as i64
    }

    /// Half the nominal period to the nearest microsecond (4167 at 120 Hz): a depth exposure this close to a
    /// tick belongs to that tick.
    pub fn half_period_us(&self) -> i64 {
        (self.period_us() / 2.0).round() as i64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn periods_follow_the_timeline_rate() {
        let c = TickClock::default();
        assert_eq!(c.period_s(), 1.0 / 120.0);
        assert_eq!((c.whole_period_us(), c.half_period_us()), (8_333, 4_167));
        let slow = TickClock::of(&TimelineConfig {
            tick_rate_hz: 60.0,
            ..TimelineConfig::default()
        });
        assert_eq!(
            (slow.whole_period_us(), slow.half_period_us()),
            (16_667, 8_333)
        );
    }
}

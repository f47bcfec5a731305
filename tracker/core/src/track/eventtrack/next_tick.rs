//! When the next tick will come, from the times of the last ones: what the renders prefetched for it assume.

use crate::track::clock::TickClock;

/// Tick periods remembered, microseconds.
const HISTORY: usize = 8;
/// Longest repeating pattern of periods looked for (a 120 Hz timeline on a 1 us clock repeats 8333, 8333, 8334).
const LONGEST_CYCLE: usize = 4;

/// The recent tick periods and the guesses they give for the next tick's time.
#[derive(Debug, Clone)]
pub(super) struct NextTick {
    /// The nominal period, microseconds: the guess before two ticks were seen.
    nominal_us: f64,
    last_us: Option<i64>,
    /// The latest periods, oldest first (a ring of [`HISTORY`] once full).
    periods: [i64; HISTORY],
    count: usize,
}

impl NextTick {
    /// No tick seen yet, on `clock`.
    pub(super) fn new(clock: TickClock) -> Self {
        Self {
            nominal_us: clock.period_us(),
            last_us: None,
            periods: [0; HISTORY],
            count: 0,
        }
    }

    /// Records a tick at `t_us`.
    pub(super) fn record(&mut self, t_us: i64) {
        if let Some(last) = self.last_us {
            self.periods.rotate_left(1);
            self.periods[HISTORY - 1] = t_us - last;
            self.count = (self.count + 1).min(HISTORY);
        }
        self.last_us = Some(t_us);
    }

    /// The times the next tick may come at, microseconds, and how many of the two there are: one when the
    /// remembered periods repeat a pattern of at most [`LONGEST_CYCLE`] periods (the next period continues it),
    /// else the whole microsecond at or below the mean period and the one after it; none before the first tick.
    pub(super) fn candidates(&self) -> ([i64; 2], usize) {
        let Some(last) = self.last_us else {
            return ([0; 2], 0);
        };
        let recent = &self.periods[HISTORY - self.count..];
        // The shortest pattern that all remembered periods repeat, seen at least twice.
        for cycle in 1..=LONGEST_CYCLE {
            if recent.len() >= 2 * cycle && recent[cycle..].iter().zip(recent).all(|(a, b)| a == b)
            {
                return ([last + recent[recent.len() - cycle], 0], 1);
            }
        }
        let mean = if recent.is_empty() {
            self.nominal_us
        } else {
            recent.iter().sum::<i64>() as f64 / recent.len() as f64
        };
        // A whole-microsecond mean (one period seen, say 8333) does not say whether 8334 comes next: both.
        let early = (last as f64 + mean).floor() as i64;
        ([early, early + 1], 2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn guesses(n: &NextTick) -> Vec<i64> {
        let (c, k) = n.candidates();
        c[..k].to_vec()
    }

    proptest! {
        /// A timeline at a rate whose period is a whole number of microseconds over 1 to 4 ticks (120 Hz, 100 Hz,
        /// 30 Hz, 90 Hz ...), rounded to the microsecond from any phase: after two cycles, one guess, and right.
        #[test]
        fn a_regular_timeline_is_guessed_exactly(
            whole in 2_000i64..40_000,
            cycle in 1i64..=4,
            start in 0i64..1_000_000,
            phase in 0.0f64..1.0,
        ) {
            let period = whole as f64 / cycle as f64;
            let t = |k: i64| start + (k as f64 * period + phase).round() as i64;
            let mut n = NextTick::new(TickClock::default());
            for k in 0..40 {
                if k > 2 * cycle {
                    prop_assert_eq!(guesses(&n), vec![t(k)]);
                }
                n.record(t(k));
            }
        }

        /// Jitter breaks the pattern: then the two whole microseconds around the mean period.
        #[test]
        fn an_irregular_timeline_gets_two_neighbouring_guesses(jitter in proptest::collection::vec(-3i64..=3, 9)) {
            let mut n = NextTick::new(TickClock::default());
            let mut t = 0;
            for j in &jitter {
                t += 8_333 + j;
                n.record(t);
            }
            let g = guesses(&n);
            prop_assert!(g.len() <= 2 && !g.is_empty());
            if g.len() == 2 {
                prop_assert_eq!(g[1], g[0] + 1);
            } else {
                // One guess only when the 8 periods (between the 9 ticks) repeat a pattern of at most 4.
                let periods = &jitter[1..];
                let repeats = (1..=4).any(|c| periods[c..].iter().zip(periods).all(|(a, b)| a == b));
                prop_assert!(repeats, "one guess for periods {:?}", periods);
            }
            prop_assert!((g[0] - t - 8_333).abs() <= 3);
        }
    }

    #[test]
    fn repeated_ticks_and_no_ticks() {
        let mut n = NextTick::new(TickClock::default());
        assert!(guesses(&n).is_empty());
        n.record(500);
        // One tick: a nominal 120 Hz period.
        assert_eq!(guesses(&n), vec![8_833, 8_834]);
        n.record(500);
        // One period of 0: the tick may repeat, or come a microsecond later.
        assert_eq!(guesses(&n), vec![500, 501]);
        n.record(500);
        assert_eq!(guesses(&n), vec![500]);
        // 120 Hz after one period: 8333 or 8334.
        let mut n = NextTick::new(TickClock::default());
        n.record(500);
        n.record(8_833);
        assert_eq!(guesses(&n), vec![17_166, 17_167]);
    }
}

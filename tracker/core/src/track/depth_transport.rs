//! When a depth frame reaches the host: a live depth camera's transport delivers each frame some tens of
//! milliseconds after its exposure, by a latency that varies from frame to frame, and in order. The offline driver
//! ([`super::track_recording_timed`]) and the runtime's replay both simulate it with a [`DepthTransport`], so the
//! two hand every frame over at the same stream time.

/// A simulated depth transport: each frame arrives `latency_us` plus up to `jitter_us` after its exposure, never
/// before the frame exposed before it.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct DepthTransport {
    /// Fixed part of the latency, microseconds (at least 0).
    pub latency_us: i64,
    /// Largest extra latency, microseconds (at least 0): each frame adds a share of it drawn from its exposure
    /// time, the same in every run and driver.
    pub jitter_us: i64,
    last_due_us: Option<i64>,
}

impl DepthTransport {
    /// A transport with `latency_us` and up to `jitter_us` more (negative values count as 0).
    pub fn new(latency_us: i64, jitter_us: i64) -> Self {
        Self {
            latency_us: latency_us.max(0),
            jitter_us: jitter_us.max(0),
            last_due_us: None,
        }
    }

    /// Whether frames arrive with their own tick (no latency, no jitter).
    pub fn is_immediate(&self) -> bool {
        self.latency_us == 0 && self.jitter_us == 0
    }

    /// When the frame exposed at `exposed_us` arrives, stream time in microseconds. Call once per frame, in
    /// exposure order: a frame never arrives before the one exposed before it.
    pub fn due_us(&mut self, exposed_us: i64) -> i64 {
        let extra = if self.jitter_us > 0 {
            (self.jitter_us as f64 * unit_draw(exposed_us)) as i64
        } else {
            0
        };
        let due = exposed_us
            .saturating_add(self.latency_us)
            .saturating_add(extra);
        let due = self.last_due_us.map_or(due, |last| due.max(last));
        self.last_due_us = Some(due);
        due
    }
}

/// A number in [0, 1) drawn from `key` (SplitMix64's finaliser): a fixed, well-spread function of the key.
fn unit_draw(key: i64) -> f64 {
    let mut z = (key as u64).wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 53) as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn a_fixed_latency_delays_every_frame_by_it() {
        let mut t = DepthTransport::new(20_000, 0);
        assert!(!t.is_immediate());
        assert_eq!(t.due_us(1_000), 21_000);
        assert_eq!(t.due_us(34_333), 54_333);
        assert!(DepthTransport::new(0, 0).is_immediate());
        assert_eq!(DepthTransport::new(-5, -5), DepthTransport::new(0, 0));
    }

    #[test]
    fn jitter_spreads_the_arrivals_over_its_range() {
        let mut t = DepthTransport::new(20_000, 20_000);
        let extra: Vec<i64> = (0..300)
            .map(|k| {
                let exposed = 1_000 + k * 33_333;
                t.due_us(exposed) - exposed - 20_000
            })
            .collect();
        assert!(extra.iter().all(|e| (0..20_000).contains(e)), "{extra:?}");
        let low = extra.iter().filter(|e| **e < 10_000).count();
        assert!((100..200).contains(&low), "{low} of 300 in the lower half");
        // The same draws in another run (the offline driver and the replay agree).
        let mut again = DepthTransport::new(20_000, 20_000);
        assert_eq!(again.due_us(1_000) - 21_000, extra[0]);
    }

    proptest! {
        /// Frames arrive in exposure order, never before their exposure plus the latency nor after it plus the
        /// jitter, unless an earlier frame held them back.
        #[test]
        fn arrivals_are_in_order_and_within_the_range(
            latency in 0i64..100_000,
            jitter in 0i64..100_000,
            gaps in proptest::collection::vec(1i64..50_000, 1..60),
        ) {
            let mut t = DepthTransport::new(latency, jitter);
            let mut exposed = 0i64;
            let mut last = i64::MIN;
            for g in gaps {
                exposed += g;
                let due = t.due_us(exposed);
                prop_assert!(due >= exposed + latency);
                prop_assert!(due >= last);
                prop_assert!(due < (exposed + latency + jitter).max(last) + 1);
                last = due;
            }
        }
    }
}

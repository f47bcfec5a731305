//! The offset between ROS time (the drivers' header stamps) and the event camera's clock (the EVT3 stream's
//! time), estimated from the event packets, to place depth images on the event camera's clock.
//!
//! A packet's stamp is the host time its data arrived (metavision_driver) and cannot precede the events in it, so
//! `stamp - time of its first event` is the offset plus the transport delay; its minimum over recent packets is
//! the best estimate (the delay's floor). The minimum is taken over a sliding window of about two seconds of
//! stream time so that a slow drift between the clocks is followed.

/// Stream time each half of the window covers, microseconds.
const HALF_WINDOW_US: i64 = 1_000_000;

/// Estimates `ros_time_ns - camera_time_ns`.
#[derive(Debug, Clone, Default)]
pub struct ClockOffset {
    /// Minimum of the current half window, and the stream time it started.
    current: Option<(i64, i64)>,
    /// Minimum of the previous half window.
    previous: Option<i64>,
}

impl ClockOffset {
    /// A packet stamped `stamp_ns` whose first event is at `first_event_us` on the camera's clock.
    pub fn observe(&mut self, stamp_ns: i64, first_event_us: i64) {
        let candidate = stamp_ns.saturating_sub(first_event_us.saturating_mul(1000));
        match &mut self.current {
            Some((min, started)) if first_event_us - *started < HALF_WINDOW_US => {
                *min = (*min).min(candidate);
            }
            Some((min, _)) => {
                self.previous = Some(*min);
                self.current = Some((candidate, first_event_us));
            }
            None => self.current = Some((candidate, first_event_us)),
        }
    }

    /// The current estimate, once a packet with an event was seen.
    pub fn offset_ns(&self) -> Option<i64> {
        match (self.current, self.previous) {
            (Some((c, _)), Some(p)) => Some(c.min(p)),
            (Some((c, _)), None) => Some(c),
            (None, p) => p,
        }
    }

    /// `stamp_ns` (ROS time) on the camera's clock, microseconds, once the offset is known.
    pub fn to_camera_us(&self, stamp_ns: i64) -> Option<i64> {
        self.offset_ns()
            .map(|o| stamp_ns.saturating_sub(o).div_euclid(1000))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_offset_is_the_smallest_delay_of_the_recent_packets() {
        let mut c = ClockOffset::default();
        assert_eq!(c.to_camera_us(5), None);
        let offset = 1_700_000_000_000_000_000i64;
        // Delays of 300, 120, 500 us: the estimate is the 120 us one.
        for (t, delay) in [(0i64, 300i64), (400, 120), (900, 500)] {
            c.observe(offset + (t + delay) * 1000, t);
        }
        assert_eq!(c.offset_ns(), Some(offset + 120_000));
        assert_eq!(c.to_camera_us(offset + 120_000 + 5_000_000), Some(5_000));
        // Two seconds later the clocks drifted by +2 ms: the old minimum is forgotten.
        for t in (1..=30).map(|k| 1_000_000 + k * 100_000) {
            c.observe(offset + 2_000_000 + (t + 150) * 1000, t);
        }
        assert_eq!(c.offset_ns(), Some(offset + 2_000_000 + 150_000));
    }
}

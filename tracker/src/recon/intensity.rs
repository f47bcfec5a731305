//! Intensity reconstruction `I_t` from events: a per-pixel leaky log-intensity integrator (the high-pass form of
//! the complementary filter of Scheerlinck et al., 2018, used without frames). O(1) per event, no learned weights.
//!
//! Each pixel keeps its log-intensity estimate `L` and the time of its last event. An event of polarity `p` at
//! time `t` decays `L` by `exp(-alpha (t - t_last))` and adds `+-contrast`. Reading at time `t` applies the decay
//! since the last event. The same per-pixel timestamps are the tracker's time surface (latest event per pixel).

use drivers::event::CdEvent;

/// Parameters of the log-intensity filter.
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct IntensityFilterConfig {
    /// Log-intensity step per event (the sensor's mean contrast threshold), unitless; the simulator draws
    /// thresholds from U(0.16, 0.34).
    pub contrast: f32,
    /// High-pass cut-off, 1/s: how fast the estimate forgets (larger = less smear, less static detail).
    pub cutoff_hz: f32,
}

impl Default for IntensityFilterConfig {
    fn default() -> Self {
        Self {
            contrast: 0.25,
            cutoff_hz: 20.0,
        }
    }
}

/// Sentinel "no event yet" timestamp.
const NEVER: i64 = i64::MIN / 4;

/// The full-sensor event state: log intensity and latest event time per pixel.
#[derive(Debug, Clone)]
pub struct EventSurface {
    width: u32,
    height: u32,
    config: IntensityFilterConfig,
    log_intensity: Vec<f32>,
    last_us: Vec<i64>,
    events: u64,
    out_of_bounds: u64,
}

impl EventSurface {
    /// A surface for a `width x height` sensor with every pixel at log intensity 0 and no event.
    pub fn new(width: u32, height: u32, config: IntensityFilterConfig) -> Self {
        let n = width as usize * height as usize;
        Self {
            width,
            height,
            config,
            log_intensity: vec![0.0; n],
            last_us: vec![NEVER; n],
            events: 0,
            out_of_bounds: 0,
        }
    }

    /// Sensor width, pixels.
    pub fn width(&self) -> u32 {
        self.width
    }
    /// Sensor height, pixels.
    pub fn height(&self) -> u32 {
        self.height
    }
    /// Events integrated so far.
    pub fn events(&self) -> u64 {
        self.events
    }
    /// Events ignored because they lie outside the sensor.
    pub fn out_of_bounds(&self) -> u64 {
        self.out_of_bounds
    }

    /// Integrates events (time order per pixel is assumed; the stream is time-ordered).
    pub fn integrate(&mut self, events: &[CdEvent]) {
        let alpha = self.config.cutoff_hz * 1e-6;
        let c = self.config.contrast;
        let w = self.width as usize;
        for e in events {
            if u32::from(e.x) >= self.width || u32::from(e.y) >= self.height {
                self.out_of_bounds += 1;
                continue;
            }
            let i = e.y as usize * w + e.x as usize;
            let dt = (e.t_us - self.last_us[i]).max(0) as f32;
            let decay = decay(alpha * dt);
            let step = if e.polarity { c } else { -c };
            self.log_intensity[i] = self.log_intensity[i] * decay + step;
            self.last_us[i] = e.t_us;
        }
        self.events += events.len() as u64;
    }

    /// Time of the latest event at pixel `(x, y)`, microseconds; `None` if the pixel never fired or is outside.
    #[inline]
    pub fn last_event_us(&self, x: u32, y: u32) -> Option<i64> {
        if x >= self.width || y >= self.height {
            return None;
        }
        let t = self.last_us[y as usize * self.width as usize + x as usize];
        (t != NEVER).then_some(t)
    }

    /// Columns `x0, x0 + step, ...` below `x1` of row `y` whose latest event lies in `(since_us, until_us]`
    /// (columns and rows outside the sensor yield nothing; `step` 0 counts as 1).
    pub fn recent_in_row(
        &self,
        y: u32,
        x0: u32,
        x1: u32,
        step: usize,
        since_us: i64,
        until_us: i64,
    ) -> impl Iterator<Item = u32> + '_ {
        let w = self.width as usize;
        let row: &[i64] = if y < self.height {
            &self.last_us[y as usize * w..(y as usize + 1) * w]
        } else {
            &[]
        };
        let x1 = (x1 as usize).min(row.len());
        let x0 = (x0 as usize).min(x1);
        row[x0..x1]
            .iter()
            .enumerate()
            .step_by(step.max(1))
            .filter(move |&(_, &t)| t != NEVER && t > since_us && t <= until_us)
            .map(move |(i, _)| (x0 + i) as u32)
    }

    /// Reconstructed log intensity at pixel `(x, y)` at time `t_us` (0 outside the sensor).
    #[inline]
    pub fn log_intensity_at(&self, x: u32, y: u32, t_us: i64) -> f32 {
        if x >= self.width || y >= self.height {
            return 0.0;
        }
        let i = y as usize * self.width as usize + x as usize;
        let dt = (t_us - self.last_us[i]).max(0) as f32;
        self.log_intensity[i] * decay(self.config.cutoff_hz * 1e-6 * dt)
    }
}

/// `exp(-x)` for `x >= 0`: a cheap rational form for the small arguments most events see, exact otherwise.
#[inline]
fn decay(x: f32) -> f32 {
    if x < 0.05 {
        1.0 - x + 0.5 * x * x
    } else {
        (-x).exp()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ev(t_us: i64, x: u16, y: u16, polarity: bool) -> CdEvent {
        CdEvent {
            t_us,
            x,
            y,
            polarity,
        }
    }

    #[test]
    fn events_step_log_intensity_by_the_contrast() {
        let mut s = EventSurface::new(4, 4, IntensityFilterConfig::default());
        s.integrate(&[ev(10, 1, 2, true), ev(10, 1, 2, true), ev(20, 3, 0, false)]);
        assert!((s.log_intensity_at(1, 2, 10) - 0.5).abs() < 1e-3);
        assert!((s.log_intensity_at(3, 0, 20) + 0.25).abs() < 1e-6);
        assert_eq!(s.log_intensity_at(0, 0, 20), 0.0);
        assert_eq!(s.last_event_us(1, 2), Some(10));
        assert_eq!(s.last_event_us(0, 0), None);
    }

    #[test]
    fn estimate_decays_with_the_cutoff() {
        let cfg = IntensityFilterConfig {
            contrast: 1.0,
            cutoff_hz: 2.0,
        };
        let mut s = EventSurface::new(2, 2, cfg);
        s.integrate(&[ev(0, 0, 0, true)]);
        // After 0.5 s at 2 /s: exp(-1).
        let v = s.log_intensity_at(0, 0, 500_000);
        assert!((v - (-1.0f32).exp()).abs() < 1e-4, "{v}");
    }

    #[test]
    fn out_of_sensor_events_are_counted_not_written() {
        let mut s = EventSurface::new(2, 2, IntensityFilterConfig::default());
        s.integrate(&[ev(0, 5, 0, true), ev(0, 0, 9, true)]);
        assert_eq!(s.out_of_bounds(), 2);
        assert_eq!(s.last_event_us(1, 1), None);
    }
}

//! Event simulation after ESIM: per-pixel log intensity, contrast thresholds, crossing times interpolated
//! linearly between renders, a refractory period and background noise events.
//!
//! The caller renders the scene at sample times close enough that no pixel moves more than about half a
//! pixel between them, and passes the new log intensity of every region that changed. Pixels outside those
//! regions keep their value, so only the changing region needs rendering.

use crate::rng::SeedRng;
use drivers::event::CdEvent;

/// Parameters of the event camera model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EsimConfig {
    /// Sequence-level contrast threshold; `None` draws it from U(0.16, 0.34) with the seed (the paper's range).
    pub contrast: Option<f64>,
    /// Standard deviation of the per-pixel thresholds around the sequence level.
    pub contrast_spread: f64,
    /// Events closer than this to the previous event of the same pixel are dropped (the pixel is blind), us.
    pub refractory_us: f64,
    /// Background noise events per pixel per second.
    pub noise_rate_hz: f64,
    /// Offset added to linear intensity before the logarithm (dark pixels are less sensitive).
    pub log_eps: f32,
}

impl Default for EsimConfig {
    fn default() -> Self {
        Self {
            contrast: None,
            contrast_spread: 0.03,
            refractory_us: 50.0,
            noise_rate_hz: 0.05,
            log_eps: 0.02,
        }
    }
}

/// Counters of what the simulator produced and dropped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct EsimStats {
    /// Signal events emitted.
    pub signal_events: u64,
    /// Noise events emitted.
    pub noise_events: u64,
    /// Threshold crossings dropped by the refractory period.
    pub refractory_dropped: u64,
}

/// The per-pixel state of a simulated event sensor.
#[derive(Debug, Clone)]
pub struct EventSimulator {
    width: u32,
    height: u32,
    config: EsimConfig,
    contrast: f64,
    c_pos: Vec<f32>,
    c_neg: Vec<f32>,
    reference: Vec<f32>,
    last: Vec<f32>,
    last_event_us: Vec<f64>,
    rng: SeedRng,
    stats: EsimStats,
}

impl EventSimulator {
    /// A sensor of `width x height` pixels whose log intensity starts at `initial_log` (row-major).
    pub fn new(
        width: u32,
        height: u32,
        config: EsimConfig,
        seed: u64,
        initial_log: &[f32],
    ) -> Self {
        let n = width as usize * height as usize;
        assert_eq!(
            initial_log.len(),
            n,
            "initial log image must be width x height"
        );
        let mut rng = SeedRng::new(seed ^ 0xE51E);
        let contrast = config.contrast.unwrap_or_else(|| rng.range(0.16, 0.34));
        let draw =
            |rng: &mut SeedRng| (contrast + config.contrast_spread * rng.normal()).max(0.05) as f32;
        let c_pos = (0..n).map(|_| draw(&mut rng)).collect();
        let c_neg = (0..n).map(|_| draw(&mut rng)).collect();
        Self {
            width,
            height,
            config,
            contrast,
            c_pos,
            c_neg,
            reference: initial_log.to_vec(),
            last: initial_log.to_vec(),
            last_event_us: vec![f64::NEG_INFINITY; n],
            rng,
            stats: EsimStats::default(),
        }
    }

    /// Log intensity of linear intensity `i` as the sensor sees it.
    #[inline]
    pub fn log_intensity(&self, i: f32) -> f32 {
        (i.max(0.0) + self.config.log_eps).ln()
    }

    /// The sequence-level contrast threshold.
    pub fn contrast(&self) -> f64 {
        self.contrast
    }

    /// Per-pixel ON and OFF thresholds of pixel `(x, y)`.
    pub fn thresholds(&self, x: u32, y: u32) -> (f32, f32) {
        let i = (y * self.width + x) as usize;
        (self.c_pos[i], self.c_neg[i])
    }

    /// Counters so far.
    pub fn stats(&self) -> EsimStats {
        self.stats
    }

    /// Advances the pixels of the region `(x0, y0, w, h)` from their last values (at `t0_us`) to `log`
    /// (row-major `w x h`, at `t1_us`), appending events with crossing times interpolated in between.
    #[allow(clippy::too_many_arguments)]
    pub fn update_region(
        &mut self,
        t0_us: f64,
        t1_us: f64,
        x0: u32,
        y0: u32,
        w: u32,
        h: u32,
        log: &[f32],
        out: &mut Vec<CdEvent>,
    ) {
        let span = t1_us - t0_us;
        let refractory = self.config.refractory_us;
        // A crossing exactly at t1 keeps t1: the next interval's events are all at t1 or later.
        let last_us = t1_us.floor() as i64;
        for ry in 0..h {
            let y = y0 + ry;
            if y >= self.height {
                break;
            }
            for rx in 0..w {
                let x = x0 + rx;
                if x >= self.width {
                    break;
                }
                let i = (y * self.width + x) as usize;
                let new = log[(ry * w + rx) as usize];
                let old = self.last[i];
                self.last[i] = new;
                let d = new - old;
                if d == 0.0 {
                    continue;
                }
                let (c, polarity, sign) = if d > 0.0 {
                    (self.c_pos[i], true, 1.0)
                } else {
                    (self.c_neg[i], false, -1.0)
                };
                let mut r = self.reference[i];
                while sign * (new - r) >= c {
                    r += sign * c;
                    let t = t0_us + f64::from((r - old) / d) * span;
                    if t - self.last_event_us[i] < refractory {
                        self.stats.refractory_dropped += 1;
                        continue;
                    }
                    self.last_event_us[i] = t;
                    let t_us = (t.floor() as i64).clamp(t0_us.floor() as i64, last_us);
                    out.push(CdEvent {
                        t_us,
                        x: x as u16,
                        y: y as u16,
                        polarity,
                    });
                    self.stats.signal_events += 1;
                }
                self.reference[i] = r;
            }
        }
    }

    /// Appends background noise events in `[t0_us, t1_us)`: Poisson in count, uniform over pixels and time,
    /// either polarity. Noise does not move the pixels' references.
    pub fn noise(&mut self, t0_us: f64, t1_us: f64, out: &mut Vec<CdEvent>) {
        let n_px = f64::from(self.width) * f64::from(self.height);
        let expected = self.config.noise_rate_hz * n_px * (t1_us - t0_us) * 1e-6;
        let n = expected.floor() as u64 + u64::from(self.rng.uniform() < expected.fract());
        let (a, b) = (
            t0_us.floor() as i64,
            (t1_us.ceil() as i64 - 1).max(t0_us.floor() as i64),
        );
        for _ in 0..n {
            let x = (self.rng.uniform() * f64::from(self.width)) as u16;
            let y = (self.rng.uniform() * f64::from(self.height)) as u16;
            let t = (t0_us + self.rng.uniform() * (t1_us - t0_us)).floor() as i64;
            out.push(CdEvent {
                t_us: t.clamp(a, b),
                x,
                y,
                polarity: self.rng.uniform() < 0.5,
            });
        }
        self.stats.noise_events += n;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sim(contrast: f64, initial: f32) -> EventSimulator {
        let cfg = EsimConfig {
            contrast: Some(contrast),
            contrast_spread: 0.0,
            refractory_us: 0.0,
            noise_rate_hz: 0.0,
            log_eps: 0.0,
        };
        EventSimulator::new(4, 1, cfg, 1, &[initial; 4])
    }

    #[test]
    fn a_ramp_fires_one_event_per_threshold_at_interpolated_times() {
        let mut s = sim(0.2, 0.0);
        let mut out = Vec::new();
        // Pixel 1 rises by 0.5 over 1000 us: crossings at 0.2 and 0.4, i.e. 400 and 800 us.
        s.update_region(0.0, 1000.0, 1, 0, 1, 1, &[0.5], &mut out);
        assert_eq!(out.len(), 2);
        assert_eq!((out[0].t_us, out[1].t_us), (400, 800));
        assert!(out.iter().all(|e| e.polarity && e.x == 1));
        // The reference is now 0.4; falling from 0.5 to 0.0 crosses 0.2 and 0.0, at 1600 and 2000 us.
        out.clear();
        s.update_region(1000.0, 2000.0, 1, 0, 1, 1, &[0.0], &mut out);
        assert_eq!(
            out.iter().map(|e| e.t_us).collect::<Vec<_>>(),
            vec![1600, 2000]
        );
        assert!(out.iter().all(|e| !e.polarity));
    }

    #[test]
    fn refractory_period_drops_close_events() {
        let mut s = sim(0.1, 0.0);
        s.config.refractory_us = 300.0;
        let mut out = Vec::new();
        // Ten crossings about 95 us apart: only every fourth is 300 us after the last kept one.
        s.update_region(0.0, 1000.0, 0, 0, 1, 1, &[1.05], &mut out);
        assert_eq!(
            out.iter().map(|e| e.t_us).collect::<Vec<_>>(),
            vec![95, 476, 857]
        );
        assert_eq!(s.stats().refractory_dropped, 7);
    }

    #[test]
    fn noise_rate_matches() {
        let cfg = EsimConfig {
            noise_rate_hz: 2.0,
            ..EsimConfig::default()
        };
        let mut s = EventSimulator::new(100, 100, cfg, 3, &vec![0.0; 10_000]);
        let mut out = Vec::new();
        s.noise(0.0, 1e6, &mut out);
        // 20,000 expected.
        assert!((19_000..21_000).contains(&out.len()), "{}", out.len());
        assert!(out.iter().all(|e| (0..1_000_000).contains(&e.t_us)));
    }

    #[test]
    fn thresholds_follow_the_paper_range() {
        for seed in 0..50 {
            let s = EventSimulator::new(2, 2, EsimConfig::default(), seed, &[0.0; 4]);
            assert!((0.16..0.34).contains(&s.contrast()));
        }
    }
}

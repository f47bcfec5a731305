//! The simplest synthetic scene: a bar rotating about the image centre, as an EVT 3.0 stream carrying the
//! rig's trigger schedule. It needs no meshes or renderer, so it is the smoke test of the event and trigger
//! path (`eventtrack6d inspect` on it shows the 120 Hz timeline with its depth exposures).

use drivers::event::{CdEvent, Geometry, TriggerEdge};
use drivers::formats::any::EventFormat;
use drivers::raw::{RawHeader, RawWriteError, RawWriter};
use drivers::timeline::{TimelineConfig, ideal_edges};
use std::f64::consts::TAU;
use std::io::Write;

/// Parameters of the rotating-bar pattern.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RotatingBar {
    /// Sensor size.
    pub geometry: Geometry,
    /// Length of the stream, seconds.
    pub seconds: f64,
    /// Rotation rate, revolutions per second.
    pub revolutions_per_s: f64,
    /// Bar extent from the centre: inner and outer radius, pixels.
    pub radii_px: (f64, f64),
    /// Bar width, pixels.
    pub width_px: f64,
    /// Background noise events per pixel per second.
    pub noise_rate_hz: f64,
    /// Seed of the noise.
    pub seed: u64,
}

impl Default for RotatingBar {
    fn default() -> Self {
        Self {
            geometry: Geometry::new(1280, 720),
            seconds: 2.0,
            revolutions_per_s: 1.0,
            radii_px: (40.0, 320.0),
            width_px: 12.0,
            noise_rate_hz: 0.1,
            seed: 1,
        }
    }
}

/// What [`write_rotating_bar`] wrote.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PatternStats {
    /// CD events written.
    pub cd_events: u64,
    /// Trigger edges written.
    pub trigger_edges: u64,
}

/// Writes the pattern as a `.raw` EVT 3.0 stream to `out`, in 10 ms slices (memory stays bounded).
pub fn write_rotating_bar(p: &RotatingBar, out: impl Write) -> Result<PatternStats, RawWriteError> {
    let header = RawHeader::new(
        EventFormat::Evt3,
        p.geometry,
        &[("generator", "hil-sim pattern")],
    );
    let mut w = RawWriter::new(out, &header)?;
    let total_us = (p.seconds * 1e6).round() as i64;
    let ticks = (p.seconds * TimelineConfig::default().tick_rate_hz).floor() as u64;
    let edges = ideal_edges(&TimelineConfig::default(), 0, ticks);
    let omega = TAU * p.revolutions_per_s;
    let (cx, cy) = (
        f64::from(p.geometry.width) / 2.0,
        f64::from(p.geometry.height) / 2.0,
    );
    let mut rng = p.seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut stats = PatternStats {
        cd_events: 0,
        trigger_edges: 0,
    };
    let slice_us = 10_000;
    let mut cd = Vec::new();
    let mut t0 = 0;
    while t0 < total_us {
        let t1 = (t0 + slice_us).min(total_us);
        cd.clear();
        bar_events(p, omega, (cx, cy), t0, t1, &mut cd);
        noise_events(p, &mut rng, t0, t1, &mut cd);
        cd.sort_by_key(|e| (e.t_us, e.y, e.polarity, e.x));
        let tr: Vec<TriggerEdge> = edges
            .iter()
            .copied()
            .filter(|e| e.t_us >= t0 && e.t_us < t1)
            .collect();
        w.write(&cd, &tr)?;
        stats.cd_events += cd.len() as u64;
        stats.trigger_edges += tr.len() as u64;
        t0 = t1;
    }
    w.finish()?;
    Ok(stats)
}

/// Events of the bar's leading (ON) and trailing (OFF) edges crossing each pixel within `[t0, t1)`.
fn bar_events(
    p: &RotatingBar,
    omega: f64,
    (cx, cy): (f64, f64),
    t0: i64,
    t1: i64,
    out: &mut Vec<CdEvent>,
) {
    let (r0, r1) = p.radii_px;
    let y_lo = (cy - r1).floor().max(0.0) as u16;
    let y_hi = (cy + r1).ceil().min(f64::from(p.geometry.height) - 1.0) as u16;
    let x_lo = (cx - r1).floor().max(0.0) as u16;
    let x_hi = (cx + r1).ceil().min(f64::from(p.geometry.width) - 1.0) as u16;
    let (a0, a1) = (omega * t0 as f64 * 1e-6, omega * t1 as f64 * 1e-6);
    for y in y_lo..=y_hi {
        for x in x_lo..=x_hi {
            let (dx, dy) = (f64::from(x) + 0.5 - cx, f64::from(y) + 0.5 - cy);
            let r = dx.hypot(dy);
            if r < r0 || r > r1 {
                continue;
            }
            let phi = dy.atan2(dx).rem_euclid(TAU);
            let half = (p.width_px / 2.0) / r;
            for (offset, polarity) in [(-half, true), (half, false)] {
                // Angles at which this edge passes the pixel: phi + offset + k * TAU.
                let base = phi + offset;
                let k0 = ((a0 - base) / TAU).ceil() as i64;
                let mut k = k0;
                loop {
                    let a = base + k as f64 * TAU;
                    if a >= a1 {
                        break;
                    }
                    if a >= a0 {
                        let t = (a / omega * 1e6).floor() as i64;
                        out.push(CdEvent {
                            t_us: t.clamp(t0, t1 - 1),
                            x,
                            y,
                            polarity,
                        });
                    }
                    k += 1;
                }
            }
        }
    }
}

fn noise_events(p: &RotatingBar, rng: &mut u64, t0: i64, t1: i64, out: &mut Vec<CdEvent>) {
    let pixels = f64::from(p.geometry.width) * f64::from(p.geometry.height);
    let n = (pixels * p.noise_rate_hz * (t1 - t0) as f64 * 1e-6).round() as u64;
    for _ in 0..n {
        let mut next = || {
            *rng ^= *rng << 13;
            *rng ^= *rng >> 7;
            *rng ^= *rng << 17;
            *rng
        };
        let x = (next() % u64::from(p.geometry.width)) as u16;
        let y = (next() % u64::from(p.geometry.height)) as u16;
        let t = t0 + (next() % (t1 - t0) as u64) as i64;
        out.push(CdEvent {
            t_us: t,
            x,
            y,
            polarity: next() & 1 == 1,
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use drivers::event::EventBuffer;
    use drivers::raw::RawReader;
    use std::path::Path;

    #[test]
    fn each_covered_pixel_fires_on_then_off_once_per_revolution() {
        let p = RotatingBar {
            seconds: 1.0,
            noise_rate_hz: 0.0,
            ..RotatingBar::default()
        };
        let mut bytes = Vec::new();
        let stats = write_rotating_bar(&p, &mut bytes).unwrap();
        let mut r = RawReader::new(&bytes[..], Path::new("pattern.raw")).unwrap();
        let mut b = EventBuffer::new();
        r.read_all(&mut b).unwrap();
        assert_eq!(r.anomalies().total(), 0);
        assert_eq!(b.cd.len() as u64, stats.cd_events);
        assert_eq!(
            b.triggers.len(),
            240,
            "120 pulses = 240 edges in one second"
        );
        // A pixel on the bar's path at radius 100 px, 90 degrees from the start: ON at a quarter turn.
        let (x, y) = (640u16, 360u16 + 100);
        let px: Vec<&CdEvent> = b.cd.iter().filter(|e| e.x == x && e.y == y).collect();
        assert_eq!(px.len(), 2, "{px:?}");
        assert!(px[0].polarity && !px[1].polarity);
        assert!(
            (px[0].t_us - 250_000).abs() < 20_000,
            "ON at {} us",
            px[0].t_us
        );
        // Area of the annulus: about one ON and one OFF per pixel per revolution.
        let area = std::f64::consts::PI * (320.0f64.powi(2) - 40.0f64.powi(2));
        let ratio = b.cd.len() as f64 / (2.0 * area);
        assert!(
            (0.95..1.05).contains(&ratio),
            "events per covered pixel {ratio}"
        );
    }
}

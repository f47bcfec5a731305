//! Intensity reconstruction `I_t` from events: a per-pixel leaky log-intensity integrator (the high-pass form of
//! the complementary filter of Scheerlinck et al., 2018, used without frames). O(1) per event, no learned weights.
//!
//! Each pixel keeps its log-intensity estimate `L` and the time of its last event. An event of polarity `p` at
//! time `t` decays `L` by `exp(-alpha (t - t_last))` and adds `+-contrast`. Reading at time `t` applies the decay
//! since the last event. The same per-pixel timestamps are the tracker's time surface (latest event per pixel).
//!
//! A surface can also keep the timestamps alone ([`EventSurface::latest_times_only`]): the event term reads only
//! those, and an event then costs one store instead of a read-decay-write of two arrays (about 4x less).

use drivers::event::CdEvent;

mod log;
use log::LoggedEvent;
pub use log::SurfaceLog;

/// Parameters of the log-intensity filter.
#[derive(
    Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize, schemars::JsonSchema,
)]
#[serde(deny_unknown_fields, default)]
pub struct IntensityFilterConfig {
    /// Log-intensity step per event (the sensor's mean contrast threshold), unitless; the simulator draws
    /// thresholds from U(0.16, 0.34).
    pub contrast: f32,
    /// High-pass cut-off, 1/s: how fast the estimate forgets (larger = less smear, less static detail).
    pub cutoff_hz: f32,
    /// Reconstruct `I_t` even when no residual term reads it (the intensity term's weight is 0), e.g. for
    /// overlays of the tracker's own state; `track --overlay` sets it. Off, and with the intensity term off, the
    /// tracker keeps only the latest event time per pixel. Poses do not depend on it.
    pub always: bool,
}

impl Default for IntensityFilterConfig {
    fn default() -> Self {
        Self {
            contrast: 0.25,
            cutoff_hz: 20.0,
            always: false,
        }
    }
}

/// Sentinel "no event yet" in the stored offsets. Decoded, it lies about 36 minutes before the base: older than
/// any window and fully decayed, so it needs no special case except where "never" must be reported.
const NEVER: i32 = i32::MIN;

/// Offset of the first event from the base, microseconds: events up to this much older than the first one are
/// stored exactly (about 9 minutes).
const BASE_MARGIN_US: i64 = 1 << 29;

/// Offsets at or past this move the base forward (about 2 minutes of headroom before the i32 range ends).
const REBASE_AT_US: i64 = i32::MAX as i64 - (1 << 27);

/// The full-sensor event state: log intensity (unless built with [`Self::latest_times_only`]) and latest event
/// time per pixel.
#[derive(Debug, Clone)]
pub struct EventSurface {
    width: u32,
    height: u32,
    config: IntensityFilterConfig,
    /// Whether `log_intensity` is kept.
    intensity: bool,
    /// Log intensity per pixel, row-major; empty if the surface keeps times only.
    log_intensity: Vec<f32>,
    /// Latest event time per pixel as an offset from `base_us`, microseconds ([`NEVER`] if none): half the
    /// memory of absolute times, which the per-tick event binning reads for a whole ROI.
    last_us: Vec<i32>,
    /// Time the offsets count from, microseconds; `None` before the first event.
    base_us: Option<i64>,
    /// Times the base moved forward.
    rebases: u64,
    events: u64,
    out_of_bounds: u64,
}

impl EventSurface {
    /// A surface for a `width x height` sensor with every pixel at log intensity 0 and no event.
    pub fn new(width: u32, height: u32, config: IntensityFilterConfig) -> Self {
        Self::with_intensity(width, height, config, true)
    }

    /// A surface for a `width x height` sensor that keeps only the latest event time per pixel:
    /// [`Self::log_intensity_at`] reads 0 everywhere.
    pub fn latest_times_only(width: u32, height: u32) -> Self {
        Self::with_intensity(width, height, IntensityFilterConfig::default(), false)
    }

    fn with_intensity(
        width: u32,
        height: u32,
        config: IntensityFilterConfig,
        intensity: bool,
    ) -> Self {
        let n = width as usize * height as usize;
        Self {
            width,
            height,
            config,
            intensity,
            log_intensity: if intensity { vec![0.0; n] } else { Vec::new() },
            last_us: vec![NEVER; n],
            base_us: None,
            rebases: 0,
            events: 0,
            out_of_bounds: 0,
        }
    }

    /// Whether the surface reconstructs the log intensity (false for [`Self::latest_times_only`]).
    pub fn reconstructs_intensity(&self) -> bool {
        self.intensity
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

    /// Times the stored offsets were moved to a later base (once every ~33 minutes of stream time; each is one
    /// pass over the sensor's pixels).
    pub fn rebases(&self) -> u64 {
        self.rebases
    }

    /// Integrates events (time order per pixel is assumed; the stream is time-ordered).
    pub fn integrate(&mut self, events: &[CdEvent]) {
        for e in events {
            if self.pixel_of(e).is_none() {
                self.out_of_bounds += 1;
                continue;
            }
            self.apply(e);
        }
        self.events += events.len() as u64;
    }

    /// Row-major index of the event's pixel; `None` outside the sensor.
    #[inline]
    fn pixel_of(&self, e: &CdEvent) -> Option<usize> {
        (u32::from(e.x) < self.width && u32::from(e.y) < self.height)
            .then(|| e.y as usize * self.width as usize + e.x as usize)
    }

    /// Applies one event inside the sensor to its pixel (decay, step, time).
    #[inline]
    fn apply(&mut self, e: &CdEvent) {
        let i = e.y as usize * self.width as usize + e.x as usize;
        let (base, offset) = self.base_and_offset(e.t_us);
        if self.intensity {
            let alpha = self.config.cutoff_hz * 1e-6;
            let c = self.config.contrast;
            let dt = (e.t_us - (base + i64::from(self.last_us[i]))).max(0) as f32;
            let decay = decay(alpha * dt);
            let step = if e.polarity { c } else { -c };
            self.log_intensity[i] = self.log_intensity[i] * decay + step;
        }
        self.last_us[i] = offset;
    }

    /// The base in use for an event at `t_us` (moved forward first if the offset would leave the storable range),
    /// and the event's stored offset. An event far older than the first one (not time-ordered) is stored as the
    /// oldest storable time.
    #[inline]
    fn base_and_offset(&mut self, t_us: i64) -> (i64, i32) {
        let base = *self.base_us.get_or_insert(t_us - BASE_MARGIN_US);
        let offset = t_us - base;
        if offset >= REBASE_AT_US {
            self.rebase(t_us - BASE_MARGIN_US);
            return (t_us - BASE_MARGIN_US, BASE_MARGIN_US as i32);
        }
        (base, offset.max(i64::from(NEVER) + 1) as i32)
    }

    /// Moves the base to `base_us`: offsets are shifted, and times older than the new range become the oldest
    /// storable time (long past any window and fully decayed).
    fn rebase(&mut self, base_us: i64) {
        let shift = base_us - self.base_us.unwrap_or(base_us);
        for v in &mut self.last_us {
            if *v != NEVER {
                *v = (i64::from(*v) - shift).max(i64::from(NEVER) + 1) as i32;
            }
        }
        self.base_us = Some(base_us);
        self.rebases += 1;
    }

    /// `t_us` as a stored offset, saturated to the storable range (so comparisons keep their sense).
    #[inline]
    fn offset_of(&self, t_us: i64) -> i32 {
        let base = self.base_us.unwrap_or(0);
        t_us.saturating_sub(base)
            .clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32
    }

    /// Time of the latest event at pixel `(x, y)`, microseconds; `None` if the pixel never fired or is outside.
    #[inline]
    pub fn last_event_us(&self, x: u32, y: u32) -> Option<i64> {
        if x >= self.width || y >= self.height {
            return None;
        }
        let t = self.last_us[y as usize * self.width as usize + x as usize];
        (t != NEVER).then(|| self.base_us.unwrap_or(0) + i64::from(t))
    }

    /// Row `y`'s stored times for columns `x0..x1` clipped to the sensor (empty outside it), the first column's
    /// index, and the window `(since_us, until_us]` as stored offsets.
    fn row_window(
        &self,
        y: u32,
        x0: u32,
        x1: u32,
        since_us: i64,
        until_us: i64,
    ) -> (&[i32], usize, i32, i32) {
        let w = self.width as usize;
        let row: &[i32] = if y < self.height {
            &self.last_us[y as usize * w..(y as usize + 1) * w]
        } else {
            &[]
        };
        let x1 = (x1 as usize).min(row.len());
        let x0 = (x0 as usize).min(x1);
        let (since, until) = (self.offset_of(since_us), self.offset_of(until_us));
        (&row[x0..x1], x0, since, until)
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
        let (span, x0, since, until) = self.row_window(y, x0, x1, since_us, until_us);
        // NEVER (i32::MIN) is never above `since`.
        span.iter()
            .enumerate()
            .step_by(step.max(1))
            .filter(move |&(_, &t)| t > since && t <= until)
            .map(move |(i, _)| (x0 + i) as u32)
    }

    /// The columns [`Self::recent_in_row`] yields, in the same order, passed to `visit`. With `step` 1 the row is
    /// tested eight pixels at a time (branch-free), which matters because most pixels of a row are quiet.
    #[allow(clippy::too_many_arguments)]
    pub fn for_each_recent_in_row(
        &self,
        y: u32,
        x0: u32,
        x1: u32,
        step: usize,
        since_us: i64,
        until_us: i64,
        mut visit: impl FnMut(u32),
    ) {
        if step > 1 {
            self.recent_in_row(y, x0, x1, step, since_us, until_us)
                .for_each(visit);
            return;
        }
        let (span, x0, since, until) = self.row_window(y, x0, x1, since_us, until_us);
        let chunks = span.chunks_exact(8);
        let tail = chunks.remainder();
        // NEVER (i32::MIN) is never above `since`.
        let recent = |t: i32| (t > since) & (t <= until);
        for (c, chunk) in chunks.enumerate() {
            let mut bits = 0u32;
            for (k, &t) in chunk.iter().enumerate() {
                bits |= u32::from(recent(t)) << k;
            }
            while bits != 0 {
                visit((x0 + c * 8 + bits.trailing_zeros() as usize) as u32);
                bits &= bits - 1;
            }
        }
        let start = x0 + span.len() - tail.len();
        for (k, &t) in tail.iter().enumerate() {
            if recent(t) {
                visit((start + k) as u32);
            }
        }
    }

    /// Reconstructed log intensity at pixel `(x, y)` at time `t_us` (0 outside the sensor, and everywhere if the
    /// surface keeps times only).
    #[inline]
    pub fn log_intensity_at(&self, x: u32, y: u32, t_us: i64) -> f32 {
        if x >= self.width || y >= self.height || !self.intensity {
            return 0.0;
        }
        let i = y as usize * self.width as usize + x as usize;
        let last = self.base_us.unwrap_or(0) + i64::from(self.last_us[i]);
        let dt = (t_us - last).max(0) as f32;
        self.log_intensity[i] * decay(self.config.cutoff_hz * 1e-6 * dt)
    }

    /// [`Self::integrate`], recording each event in `log` with its pixel's state before it. `log` must be at its
    /// latest state (not wound back).
    pub fn integrate_logged(&mut self, events: &[CdEvent], log: &mut SurfaceLog) {
        debug_assert!(log.at_latest(), "integrating into a wound-back surface");
        for e in events {
            let Some(i) = self.pixel_of(e) else {
                self.out_of_bounds += 1;
                continue;
            };
            let entry = LoggedEvent {
                event: *e,
                previous_time: self.last_us[i],
                previous_intensity: self.log_intensity.get(i).copied().unwrap_or(0.0),
            };
            let rebases = self.rebases;
            self.apply(e);
            log.push(entry);
            if self.rebases != rebases {
                // The stored times moved: the logged ones no longer match them.
                log.restart();
            }
        }
        self.events += events.len() as u64;
    }

    /// Winds the surface back to `position` of `log` (as it was when that many events had been logged), undoing
    /// the later events newest first. Returns `false`, changing nothing, if the log no longer reaches it.
    pub fn wind_back(&mut self, log: &mut SurfaceLog, position: u64) -> bool {
        if !log.reaches(position) {
            return false;
        }
        if position >= log.applied {
            return true;
        }
        let (from, to) = (
            (position - log.first) as usize,
            (log.applied - log.first) as usize,
        );
        let width = self.width as usize;
        let undone = log.entries.range(from..to).rev();
        if self.log_intensity.is_empty() {
            for entry in undone {
                self.last_us[entry.event.y as usize * width + entry.event.x as usize] =
                    entry.previous_time;
            }
        } else {
            for entry in undone {
                let i = entry.event.y as usize * width + entry.event.x as usize;
                self.last_us[i] = entry.previous_time;
                self.log_intensity[i] = entry.previous_intensity;
            }
        }
        log.applied = position;
        true
    }

    /// Applies the logged events not yet applied, oldest first, up to `position` (at most the log's end). The
    /// surface ends as it was when those events first came.
    pub fn wind_forward(&mut self, log: &mut SurfaceLog, position: u64) {
        let until = position.min(log.end()).max(log.applied);
        let (from, to) = (
            (log.applied - log.first) as usize,
            (until - log.first) as usize,
        );
        for entry in log.entries.range(from..to) {
            self.apply(&entry.event);
        }
        log.applied = until;
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
            ..Default::default()
        };
        let mut s = EventSurface::new(2, 2, cfg);
        s.integrate(&[ev(0, 0, 0, true)]);
        // After 0.5 s at 2 /s: exp(-1).
        let v = s.log_intensity_at(0, 0, 500_000);
        assert!((v - (-1.0f32).exp()).abs() < 1e-4, "{v}");
    }

    #[test]
    fn times_survive_rebasing_and_windows_keep_their_sense() {
        let mut s = EventSurface::new(3, 1, IntensityFilterConfig::default());
        let t0 = 1_000_000_000_i64;
        s.integrate(&[ev(t0, 0, 0, true)]);
        // An hour later (past the i32 range of the first base): the base moves, times stay exact.
        let t1 = t0 + 3_600_000_000;
        s.integrate(&[ev(t1, 1, 0, true), ev(t1 + 5, 2, 0, false)]);
        assert_eq!(s.rebases(), 1);
        assert_eq!(s.last_event_us(1, 0), Some(t1));
        assert_eq!(s.last_event_us(2, 0), Some(t1 + 5));
        // The hour-old event is older than the new range: stored as the oldest time, still "an event".
        let old = s.last_event_us(0, 0).expect("kept");
        assert!(old < t1 - 1_800_000_000, "{old}");
        let recent: Vec<u32> = s.recent_in_row(0, 0, 3, 1, t1 - 10, t1 + 10).collect();
        assert_eq!(recent, vec![1, 2]);
        let only_first: Vec<u32> = s.recent_in_row(0, 0, 3, 1, t1 - 10, t1).collect();
        assert_eq!(only_first, vec![1]);
        // Windows reaching far outside the stored range saturate instead of wrapping.
        let all: Vec<u32> = s
            .recent_in_row(0, 0, 3, 1, i64::MIN / 2, i64::MAX / 2)
            .collect();
        assert_eq!(all, vec![0, 1, 2]);
        assert!((s.log_intensity_at(1, 0, t1) - 0.25).abs() < 1e-6);
    }

    proptest::proptest! {
        /// The chunked row scan visits exactly the columns the plain iterator yields, for any row, window, stride
        /// and column range (including ranges past the sensor and empty windows).
        #[test]
        fn chunked_row_scan_matches_the_iterator(
            times in proptest::collection::vec(proptest::option::of(0i64..2_000), 1..70),
            since in -100i64..2_100,
            len in -50i64..2_000,
            step in 0usize..4,
            x0 in 0u32..80,
            x1 in 0u32..90,
            y in 0u32..2,
        ) {
            let width = times.len() as u32;
            let mut s = EventSurface::new(width, 1, IntensityFilterConfig::default());
            let mut events: Vec<CdEvent> = times
                .iter()
                .enumerate()
                .filter_map(|(x, t)| t.map(|t| ev(t, x as u16, 0, true)))
                .collect();
            events.sort_by_key(|e| e.t_us);
            s.integrate(&events);
            let until = since + len;
            let expected: Vec<u32> = s.recent_in_row(y, x0, x1, step, since, until).collect();
            let mut got = Vec::new();
            s.for_each_recent_in_row(y, x0, x1, step, since, until, |x| got.push(x));
            proptest::prop_assert_eq!(got, expected);
        }
    }

    proptest::proptest! {
        /// A times-only surface stores exactly the times (and counts) of a full one, across rebases and
        /// out-of-sensor events, and reads no intensity.
        #[test]
        fn times_only_surface_keeps_the_same_times(
            steps in proptest::collection::vec((0i64..3_000_000_000, 0u16..5, 0u16..4, proptest::bool::ANY), 0..40),
        ) {
            let mut t = 1_000_000i64;
            let events: Vec<CdEvent> = steps
                .iter()
                .map(|&(dt, x, y, p)| {
                    t += dt;
                    ev(t, x, y, p)
                })
                .collect();
            let mut full = EventSurface::new(4, 3, IntensityFilterConfig::default());
            let mut times = EventSurface::latest_times_only(4, 3);
            for chunk in events.chunks(7) {
                full.integrate(chunk);
                times.integrate(chunk);
            }
            proptest::prop_assert!(full.reconstructs_intensity());
            proptest::prop_assert!(!times.reconstructs_intensity());
            proptest::prop_assert_eq!(full.events(), times.events());
            proptest::prop_assert_eq!(full.out_of_bounds(), times.out_of_bounds());
            proptest::prop_assert_eq!(full.rebases(), times.rebases());
            for y in 0..4 {
                for x in 0..5 {
                    proptest::prop_assert_eq!(full.last_event_us(x, y), times.last_event_us(x, y));
                    proptest::prop_assert_eq!(times.log_intensity_at(x, y, t), 0.0);
                }
            }
        }
    }

    #[test]
    fn out_of_sensor_events_are_counted_not_written() {
        let mut s = EventSurface::new(2, 2, IntensityFilterConfig::default());
        s.integrate(&[ev(0, 5, 0, true), ev(0, 0, 9, true)]);
        assert_eq!(s.out_of_bounds(), 2);
        assert_eq!(s.last_event_us(1, 1), None);
    }
}

//! The events of one ROI on its grid ([`EventBins`]): binning the recent events, removing isolated bins and
//! events that belong to a nearer object, and keeping the hinge's candidates outside the silhouette. The binning
//! reads only the events, so the tracker does it before it waits for the ROI render ([`EventBins::bin_ahead`]);
//! the rest needs the render's mask and depth.

use super::term::{EventTerm, EventTermKind};
use crate::recon::EventSurface;
use crate::refine::ModelView;
use nalgebra::Isometry3;
use scene::geometry::{PinholeCamera, Roi};
use scene::render::MASK_EMPTY;

/// Which events a binning holds: those of `roi` in the window `[t_us - window_us, t_us]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BinnedWindow {
    /// Tick time, microseconds (camera clock).
    pub t_us: i64,
    /// Window length, microseconds.
    pub window_us: i64,
    /// The ROI whose grid the events were binned on.
    pub roi: Roi,
}

/// The recent events of one ROI, binned on the ROI grid, and the bins kept after the noise and occluder filters.
#[derive(Debug, Clone, Default)]
pub(super) struct EventBins {
    /// Grid width, bins.
    pub(super) width: u32,
    /// Grid height, bins.
    pub(super) height: u32,
    /// Events per bin (saturating).
    hits: Vec<u8>,
    /// Per bin, whether it is kept (row-major, `width x height`).
    pub(super) kept: Vec<bool>,
    /// Centres of kept bins outside the predicted silhouette, full-image pixel coordinates (the hinge's only).
    pub(super) candidates: Vec<[f64; 2]>,
    /// Scratch: ROI column of each image column of the binning box (-1 outside).
    column_bins: Vec<i32>,
    /// Scratch: per bin, occupied bins among itself and its left and right neighbours.
    row_counts: Vec<u8>,
    /// The ROI of the latest binning.
    pub(super) roi: Option<Roi>,
    /// Kept bins of the latest collection.
    pub(super) kept_bins: usize,
    /// Kept bins outside the predicted silhouette.
    pub(super) outside: usize,
    /// The window [`Self::bin_ahead`] binned, until [`Self::collect`] or [`Self::take_prebinned`].
    prebinned: Option<BinnedWindow>,
}

impl EventBins {
    /// Bins the events of `surface` in `window` ahead of [`Self::collect`] (which reuses them if its call names the
    /// same window, and bins again otherwise): the part of the gathering that needs no render.
    pub fn bin_ahead(&mut self, surface: &EventSurface, window: BinnedWindow) {
        self.bin(surface, &window.roi, window.t_us, window.window_us);
        self.prebinned = Some(window);
    }

    /// Forgets a binning made by [`Self::bin_ahead`] and returns its window, if any: the next
    /// [`Self::collect`] bins afresh unless given it back.
    pub fn take_prebinned(&mut self) -> Option<BinnedWindow> {
        self.prebinned.take()
    }

    /// Bins the events of `surface` newer than `t_us - window_us` inside `roi` (the render's ROI; `mask` and
    /// `depth` are the render's mask and depth on the same grid, `id` the object's label) and keeps the candidates
    /// outside the silhouette. Events on another object's silhouette where it is nearer than `occluder_z` (metres,
    /// typically this object's centre depth) are that occluder's and are dropped; events on an object behind are
    /// kept, since this object's own leading edge sweeps over it. `prebinned` is the window a
    /// [`Self::bin_ahead`] binned (from [`Self::take_prebinned`]): if it is this one, its bins are used.
    #[allow(clippy::too_many_arguments)]
    pub fn collect(
        &mut self,
        term: &EventTerm,
        surface: &EventSurface,
        roi: &Roi,
        mask: &[u16],
        depth: &[f32],
        occluder_z: f32,
        id: u16,
        t_us: i64,
        window_us: i64,
        max_candidates: usize,
        prebinned: Option<BinnedWindow>,
    ) {
        self.prebinned = None;
        let window = BinnedWindow {
            t_us,
            window_us,
            roi: *roi,
        };
        if prebinned != Some(window) {
            self.bin(surface, roi, t_us, window_us);
        }
        self.keep(term, roi, mask, depth, occluder_z, id, max_candidates);
    }

    /// Bins the events of `surface` in `[t_us - window_us, t_us]` inside `roi` on its grid (`hits`) and counts
    /// each bin's occupied neighbours in its row (`row_counts`).
    fn bin(&mut self, surface: &EventSurface, roi: &Roi, t_us: i64, window_us: i64) {
        let (w, h) = (roi.out_width, roi.out_height);
        let n = w as usize * h as usize;
        self.width = w;
        self.height = h;
        self.roi = Some(*roi);
        self.hits.clear();
        self.hits.resize(n, 0);
        let sx = f64::from(w) / roi.width;
        let sy = f64::from(h) / roi.height;
        let x0 = roi.x.floor().max(0.0) as i64;
        let y0 = roi.y.floor().max(0.0) as i64;
        let x1 = ((roi.x + roi.width).ceil() as i64).min(i64::from(surface.width()));
        let y1 = ((roi.y + roi.height).ceil() as i64).min(i64::from(surface.height()));
        // At most about four samples per bin: larger ROIs are visited with a stride.
        let step = ((1.0 / sx).min(1.0 / sy) / 2.0).floor().max(1.0) as i64;
        let since = t_us - window_us;
        // ROI column of every image column of the box (-1 outside), shared by all rows.
        self.column_bins.clear();
        self.column_bins.extend((x0..x1.max(x0)).map(|x| {
            let i = ((x as f64 + 0.5 - roi.x) * sx) as i64;
            if i >= 0 && i < i64::from(w) {
                i as i32
            } else {
                -1
            }
        }));
        let mut y = y0;
        while y < y1 {
            let j = ((y as f64 + 0.5 - roi.y) * sy) as i64;
            if j >= 0 && j < i64::from(h) && y >= 0 {
                let row = j as usize * w as usize;
                let (bins, hits) = (&self.column_bins, &mut self.hits);
                surface.for_each_recent_in_row(
                    y as u32,
                    x0 as u32,
                    x1.max(x0) as u32,
                    step as usize,
                    since,
                    t_us,
                    |x| {
                        let i = bins[(x as i64 - x0) as usize];
                        if i >= 0 {
                            let cell = &mut hits[row + i as usize];
                            *cell = cell.saturating_add(1);
                        }
                    },
                );
            }
            y += step;
        }
        // Noise filter, first half: row sums of occupancy over each bin and its left and right neighbours
        // (`keep` adds the rows above and below). Branch-free passes over whole rows, which the compiler
        // vectorises. `row_counts` has a zero row above and below the grid, so every bin has an above and a below.
        let wu = w as usize;
        self.row_counts.clear();
        self.row_counts.resize(n + 2 * wu, 0);
        if wu > 0 {
            for (occ, out) in self
                .hits
                .chunks_exact(wu)
                .zip(self.row_counts[wu..wu + n].chunks_exact_mut(wu))
            {
                for (o, &hit) in out.iter_mut().zip(occ) {
                    *o = u8::from(hit > 0);
                }
                for (o, &hit) in out[1..].iter_mut().zip(occ) {
                    *o += u8::from(hit > 0);
                }
                for (o, &hit) in out.iter_mut().zip(&occ[1..]) {
                    *o += u8::from(hit > 0);
                }
            }
        }
    }

    /// The rest of [`Self::collect`] once the events are binned on `roi`'s grid: keeps the bins the noise filter
    /// and the occluders leave (a bin is kept if at least `min_neighbours` bins of its 3x3 neighbourhood, itself
    /// included, hold events) and, for the hinge, the candidates outside the silhouette.
    #[allow(clippy::too_many_arguments)]
    fn keep(
        &mut self,
        term: &EventTerm,
        roi: &Roi,
        mask: &[u16],
        depth: &[f32],
        occluder_z: f32,
        id: u16,
        max_candidates: usize,
    ) {
        let (w, h) = (self.width, self.height);
        let n = w as usize * h as usize;
        self.kept.clear();
        self.kept.resize(n, false);
        self.candidates.clear();
        // Sized once for the largest tick, so steady-state ticks do not allocate.
        self.candidates.reserve(max_candidates + 1);
        self.kept_bins = 0;
        self.outside = 0;
        let sx = f64::from(w) / roi.width;
        let sy = f64::from(h) / roi.height;
        let (wu, hu) = (w as usize, h as usize);
        let min = term.min_neighbours;
        let (mut bins, mut outside) = (0usize, 0usize);
        for j in 0..hu {
            let row = j * wu..(j + 1) * wu;
            let above = &self.row_counts[row.start..row.end];
            let mid = &self.row_counts[row.start + wu..row.end + wu];
            let below = &self.row_counts[row.start + 2 * wu..row.end + 2 * wu];
            let hits = &self.hits[row.clone()];
            let kept = &mut self.kept[row.clone()];
            let counts = above
                .iter()
                .zip(mid)
                .zip(below)
                .map(|((a, m), b)| a + m + b);
            let cells = kept.iter_mut().zip(hits.iter().zip(counts));
            if let (Some(labels), Some(depths)) = (mask.get(row.clone()), depth.get(row.clone())) {
                for ((k, (&hit, count)), (&label, &z)) in cells.zip(labels.iter().zip(depths)) {
                    let occluder = (label != id) & (label != MASK_EMPTY) & (z < occluder_z);
                    *k = (hit > 0) & (count >= min) & !occluder;
                    bins += usize::from(*k);
                    outside += usize::from(*k & (label != id));
                }
            } else {
                // A mask (or depth) shorter than the grid: bins past its end count as off the object.
                for ((k, (&hit, count)), i) in cells.zip(row.clone()) {
                    *k = (hit > 0) & (count >= min);
                    bins += usize::from(*k);
                    outside += usize::from(*k && mask.get(i).copied() != Some(id));
                }
            }
        }
        self.kept_bins += bins;
        self.outside += outside;
        let (wi, hi) = (w as i64, h as i64);
        if term.kind != EventTermKind::Hinge {
            // Only the hinge uses candidates.
            return;
        }
        let stride = self.outside.div_ceil(max_candidates.max(1)).max(1);
        let mut seen = 0usize;
        for j in 0..hi {
            for i in 0..wi {
                let k = (j * wi + i) as usize;
                if !self.kept[k] || mask.get(k).copied() == Some(id) {
                    continue;
                }
                if seen.is_multiple_of(stride) {
                    self.candidates.push([
                        roi.x - 0.5 + (i as f64 + 0.5) / sx,
                        roi.y - 0.5 + (j as f64 + 0.5) / sy,
                    ]);
                }
                seen += 1;
            }
        }
    }

    /// Fraction of `view`'s contour points at `pose` that have a kept event bin within two bins (event support of
    /// a moving outline); `None` without contour.
    pub fn contour_support(
        &self,
        view: &ModelView,
        pose: &Isometry3<f64>,
        camera: &PinholeCamera,
    ) -> Option<f64> {
        let roi = self.roi?;
        if view.contour.is_empty() {
            return None;
        }
        let sx = f64::from(self.width) / roi.width;
        let sy = f64::from(self.height) / roi.height;
        let (wi, hi) = (i64::from(self.width), i64::from(self.height));
        let mut supported = 0usize;
        for cp in &view.contour {
            let p = pose * cp.position;
            let Some(uv) = camera.project(&p) else {
                continue;
            };
            let i = ((uv.x + 0.5 - roi.x) * sx) as i64;
            let j = ((uv.y + 0.5 - roi.y) * sy) as i64;
            let mut hit = false;
            'search: for dj in -2..=2 {
                for di in -2..=2 {
                    let (a, b) = (i + di, j + dj);
                    if a >= 0 && b >= 0 && a < wi && b < hi && self.kept[(b * wi + a) as usize] {
                        hit = true;
                        break 'search;
                    }
                }
            }
            supported += usize::from(hit);
        }
        Some(supported as f64 / view.contour.len() as f64)
    }
}

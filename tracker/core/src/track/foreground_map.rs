//! Where the nearest foreground lies from every part of a depth frame: over the cells of the background model
//! ([`crate::track::redetect::DepthBackground`]), the nearest cell the frame shows in front of the background. A
//! pose hypothesis whose silhouette falls partly on the background is moved towards the object it nearly covers by
//! following these ways ([`crate::track::pose_search::DepthView::pull_sideways`]): a thin object (a marker, a
//! spatula's blade) is narrower than any grid of places a search can afford to try.

use crate::track::redetect::DepthBackground;

/// No foreground cell in the frame.
const NONE: u32 = u32::MAX;

/// Per cell of a depth frame, the nearest cell in front of the background (by Euclidean distance between cells,
/// propagated in two raster passes over the 8-neighbourhood: within a cell of the nearest).
#[derive(Debug, Clone, Default)]
pub(crate) struct ForegroundMap {
    cell_px: u32,
    cols: usize,
    rows: usize,
    /// Per cell (row-major), the index of the nearest foreground cell, [`NONE`] where there is none.
    nearest: Vec<u32>,
}

impl ForegroundMap {
    /// Builds the map from the cells `background` found in front of it at its latest
    /// [`DepthBackground::foreground`].
    pub fn update(&mut self, background: &DepthBackground) {
        let (front, cols, rows, cell_px) = background.front_cells();
        self.cell_px = cell_px.max(1);
        self.cols = cols;
        self.rows = rows;
        self.nearest.clear();
        self.nearest.extend(
            front
                .iter()
                .enumerate()
                .map(|(i, f)| if *f { i as u32 } else { NONE }),
        );
        if cols == 0 || rows == 0 || front.len() != cols * rows {
            self.nearest.clear();
            return;
        }
        const FORWARD: [(isize, isize); 4] = [(-1, 0), (-1, -1), (0, -1), (1, -1)];
        const BACKWARD: [(isize, isize); 4] = [(1, 0), (1, 1), (0, 1), (-1, 1)];
        for cv in 0..rows {
            for cu in 0..cols {
                self.relax(cu, cv, &FORWARD);
            }
        }
        for cv in (0..rows).rev() {
            for cu in (0..cols).rev() {
                self.relax(cu, cv, &BACKWARD);
            }
        }
    }

    /// Takes a neighbour's nearest foreground cell for cell `(cu, cv)` where it is nearer than its own.
    fn relax(&mut self, cu: usize, cv: usize, neighbours: &[(isize, isize)]) {
        let here = cv * self.cols + cu;
        let mut best = self.nearest[here];
        let mut best_d = self.distance2(here, best);
        for (du, dv) in neighbours {
            let (nu, nv) = (cu as isize + du, cv as isize + dv);
            if nu < 0 || nv < 0 || nu >= self.cols as isize || nv >= self.rows as isize {
                continue;
            }
            let site = self.nearest[nv as usize * self.cols + nu as usize];
            let d = self.distance2(here, site);
            if d < best_d {
                best = site;
                best_d = d;
            }
        }
        self.nearest[here] = best;
    }

    /// Squared distance in cells between cell `a` and the cell `site` ([`NONE`]: infinitely far).
    fn distance2(&self, a: usize, site: u32) -> u64 {
        if site == NONE {
            return u64::MAX;
        }
        let site = site as usize;
        let du = (a % self.cols).abs_diff(site % self.cols) as u64;
        let dv = (a / self.cols).abs_diff(site / self.cols) as u64;
        du * du + dv * dv
    }

    /// From the depth pixel `(u, v)`: `(0, 0)` if its cell is foreground, else the way to the centre of the nearest
    /// foreground cell, depth pixels; `None` outside the map or when the frame has no foreground.
    pub fn way_to_foreground(&self, u: f64, v: f64) -> Option<(f64, f64)> {
        if !(u >= 0.0 && v >= 0.0) {
            return None;
        }
        let cell = f64::from(self.cell_px);
        let (cu, cv) = ((u / cell) as usize, (v / cell) as usize);
        if cu >= self.cols || cv >= self.rows {
            return None;
        }
        let here = cv * self.cols + cu;
        let site = *self.nearest.get(here)?;
        if site == NONE {
            return None;
        }
        if site as usize == here {
            return Some((0.0, 0.0));
        }
        let site = site as usize;
        let centre = |c: usize| (c as f64 + 0.5) * cell;
        Some((centre(site % self.cols) - u, centre(site / self.cols) - v))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recon::DepthRig;
    use drivers::recording::DepthFrame;
    use nalgebra::Isometry3;
    use proptest::prelude::*;
    use scene::geometry::PinholeCamera;

    /// A map of a `w` x `h` pixel frame (cells of 4) whose cells `front` stand in front of a wall at 1 m.
    fn map_with(w: u32, h: u32, front: &[(u32, u32)]) -> ForegroundMap {
        let cam = PinholeCamera::new(100.0, 100.0, w as f64 / 2.0, h as f64 / 2.0, w, h).unwrap();
        let rig = DepthRig {
            camera: cam,
            event_from_depth: Isometry3::identity(),
        };
        let wall = DepthFrame {
            index: 0,
            width: w,
            height: h,
            depth_m: vec![1.0; (w * h) as usize],
        };
        let mut background = DepthBackground::new(4, w, h);
        background.update(&wall);
        let mut frame = wall.clone();
        for (cu, cv) in front {
            for y in cv * 4..cv * 4 + 4 {
                for x in cu * 4..cu * 4 + 4 {
                    frame.depth_m[(y * w + x) as usize] = 0.5;
                }
            }
        }
        let mut out = Vec::new();
        background.foreground(&frame, &rig, |_| 0.05, &mut out);
        let mut map = ForegroundMap::default();
        map.update(&background);
        map
    }

    #[test]
    fn every_pixel_points_at_the_nearest_foreground_cell() {
        // A 2 x 2 block of cells (a blob survives the foreground's isolated-noise rule).
        let map = map_with(64, 48, &[(10, 3), (11, 3), (10, 4), (11, 4)]);
        // On it: no way to go.
        assert_eq!(map.way_to_foreground(41.0, 13.0), Some((0.0, 0.0)));
        // From the left edge of the frame at its rows: straight right to the centre of cell (10, 3 or 4).
        let (du, dv) = map.way_to_foreground(2.0, 14.0).unwrap();
        assert!(
            (du - 40.0).abs() < 1e-9 && (-2.0..=2.0).contains(&dv),
            "{du} {dv}"
        );
        // From below and to the right: up and left, to the block's nearest corner cell (11, 4).
        let (du, dv) = map.way_to_foreground(62.0, 46.0).unwrap();
        assert!((du - (46.0 - 62.0)).abs() < 1e-9 && (dv - (18.0 - 46.0)).abs() < 1e-9);
        // Outside the frame: nothing.
        assert_eq!(map.way_to_foreground(-1.0, 3.0), None);
        assert_eq!(map.way_to_foreground(64.0, 3.0), None);
    }

    #[test]
    fn a_frame_without_foreground_has_no_way() {
        let map = map_with(32, 32, &[]);
        assert_eq!(map.way_to_foreground(5.0, 5.0), None);
        assert_eq!(ForegroundMap::default().way_to_foreground(0.0, 0.0), None);
    }

    proptest! {
        /// The two passes find a nearest foreground cell: none is nearer, by more than a cell, than the one the way
        /// leads to.
        #[test]
        fn the_way_leads_to_a_nearest_foreground_cell(
            blobs in proptest::collection::vec((0u32..15, 0u32..11), 1..5),
            u in 0.0f64..64.0,
            v in 0.0f64..48.0,
        ) {
            let cells: Vec<(u32, u32)> = blobs
                .iter()
                .flat_map(|(cu, cv)| [(*cu, *cv), (cu + 1, *cv), (*cu, cv + 1), (cu + 1, cv + 1)])
                .collect();
            let map = map_with(64, 48, &cells);
            let (du, dv) = map.way_to_foreground(u, v).expect("a foreground cell");
            let (cu, cv) = ((u / 4.0).floor(), (v / 4.0).floor());
            let (tu, tv) = (((u + du) / 4.0).floor(), ((v + dv) / 4.0).floor());
            let found = (tu - cu).powi(2) + (tv - cv).powi(2);
            let best = cells
                .iter()
                .map(|(a, b)| (f64::from(*a) - cu).powi(2) + (f64::from(*b) - cv).powi(2))
                .fold(f64::INFINITY, f64::min);
            prop_assert!(cells.contains(&(tu as u32, tv as u32)), "led to ({tu}, {tv}), not foreground");
            prop_assert!(found.sqrt() <= best.sqrt() + 1.0, "found {found}, nearest {best}");
        }
    }
}

//! Re-detection of an object the tracker fell off. The depth camera is static, so the scene behind the objects is
//! learned as the farthest depth seen in each cell; what stands in front of it is foreground, and object-sized
//! clusters of foreground points are the places where a lost object may be. The tracker checks each place with a
//! depth-only refinement and moves the object there if the depth agrees clearly better than where it was.

use crate::recon::DepthRig;
use drivers::recording::DepthFrame;
use nalgebra::{Matrix3, Point3, SymmetricEigen, Vector3};
use serde::{Deserialize, Serialize};

/// Re-detection parameters (`[redetect]`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct RedetectConfig {
    /// Whether an object that is `lost`, or `degraded` by more than being partly hidden, is searched for at
    /// depth frames.
    pub enabled: bool,
    /// Background model cell size, depth pixels (the depth image is sampled once per cell).
    pub cell_px: u32,
    /// A depth sample nearer than the learned background by more than this is foreground, metres...
    pub foreground_margin_m: f64,
    /// ... and by more than this many standard deviations of the depth noise at the background's depth (the
    /// background keeps the farthest of many noisy samples, so it sits above the true depth).
    pub foreground_sigmas: f64,
    /// A cluster is a candidate when it holds at least this fraction of the samples the object's two largest
    /// box extents would cover at its depth.
    pub min_support: f64,
    /// Candidate places checked per object and depth frame (besides where the tracker predicts it).
    pub candidates: usize,
    /// A candidate replaces the prediction when its score, in [0, 1], is higher by more than this... The score
    /// of a place is measured after a depth-only refinement from it: the fraction of visible model points the
    /// depth confirms times the square root of the silhouette's intersection over union with the depth measured
    /// at the object's range. Parts hidden by a nearer measurement (a hand) are left out of both.
    pub margin: f64,
    /// ... and at least this high.
    pub min_score: f64,
    /// Places checked per tick, over all objects (0: all of a depth frame's at once). Each check renders twice
    /// and refines on depth, 1.1-2.4 ms for a 160x160 ROI on one core, so a search is spread over the ticks up
    /// to the next depth frame to keep every tick inside its period; it keeps using the depth frame it was
    /// planned on. A tick's places are checked in parallel on the object threads. `depth30`, which refines only
    /// at depth frames, checks all at once.
    pub places_per_tick: usize,
    /// Whole-pose search: directions the object is tried seen from (spread evenly over the sphere), at the
    /// estimate's place and at every cluster, each in [`Self::pose_search_rolls`] turns about the line of sight;
    /// each orientation is scored by how much of its visible surface (150 points sampled on the mesh) the depth
    /// confirms. 0 turns the search off: a place is then tried only in the estimated orientation and with its
    /// longest axis along the cluster's.
    pub pose_search_views: usize,
    /// Turns about the line of sight tried per direction of [`Self::pose_search_views`].
    pub pose_search_rolls: usize,
    /// The best poses of the whole-pose search checked as places (refined on depth and scored as any place),
    /// besides the estimate's place and each cluster's own two. An object's places beyond what the ticks until
    /// the next depth frame can check (`places_per_tick` per tick, shared by the objects searched for) are left
    /// out, the clusters' last first, and counted, so that every search completes.
    pub pose_search_places: usize,
    /// Steps moving each of the whole-pose search's best coarse poses across the line of sight onto the
    /// foreground nearest its silhouette, then scored as another candidate: a thin object (a marker, a spatula's
    /// blade) is narrower than the search's sideways steps. 0 (the default) moves none: 2 lifted `fast-check`'s
    /// `spatula-rotation-fast` from 5 to 31 ADD-S but lowered both fast suites' means by 1-3 points
    /// (docs/history/tuning.md).
    pub pose_search_pulls: usize,
}

impl Default for RedetectConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            cell_px: 4,
            foreground_margin_m: 0.05,
            foreground_sigmas: 6.0,
            min_support: 0.2,
            candidates: 3,
            margin: 0.05,
            min_score: 0.15,
            places_per_tick: 2,
            pose_search_views: 24,
            pose_search_rolls: 6,
            pose_search_places: 2,
            pose_search_pulls: 0,
        }
    }
}

/// The static scene as the depth camera sees it: per cell of `cell_px` x `cell_px` depth pixels, the farthest
/// valid depth seen so far (metres, 0 = never measured). Objects and hands move, so the background behind them is
/// revealed once they have left a cell.
#[derive(Debug, Clone, Default)]
pub(crate) struct DepthBackground {
    cell_px: u32,
    cols: u32,
    rows: u32,
    width: u32,
    height: u32,
    far: Vec<f32>,
    /// Scratch: which cells are in front of the background in the frame being searched.
    front: Vec<bool>,
}

impl DepthBackground {
    /// An empty background sampled every `cell_px` depth pixels.
    pub fn new(cell_px: u32, width: u32, height: u32) -> Self {
        let mut b = Self {
            cell_px: cell_px.max(1),
            ..Self::default()
        };
        b.resize(width, height);
        b
    }

    fn resize(&mut self, width: u32, height: u32) {
        self.width = width;
        self.height = height;
        self.cols = width / self.cell_px;
        self.rows = height / self.cell_px;
        self.far.clear();
        let cells = self.cols as usize * self.rows as usize;
        self.far.resize(cells, 0.0);
        self.front.clear();
        self.front.resize(cells, false);
    }

    /// The depth pixel index sampled for cell `(cu, cv)`.
    fn sample(&self, cu: u32, cv: u32) -> usize {
        let half = self.cell_px / 2;
        (cv * self.cell_px + half) as usize * self.width as usize
            + (cu * self.cell_px + half) as usize
    }

    /// Folds `frame` in: each cell keeps the farthest valid depth seen. A frame of another size restarts the model.
    pub fn update(&mut self, frame: &DepthFrame) {
        if frame.width != self.width
            || frame.height != self.height
            || frame.depth_m.len() != frame.width as usize * frame.height as usize
        {
            self.resize(frame.width, frame.height);
            if frame.depth_m.len() != frame.width as usize * frame.height as usize {
                return;
            }
        }
        for cv in 0..self.rows {
            for cu in 0..self.cols {
                let z = frame.depth_m[self.sample(cu, cv)];
                let far = &mut self.far[(cv * self.cols + cu) as usize];
                if z.is_finite() && z > *far {
                    *far = z;
                }
            }
        }
    }

    /// Whether the depth pixel `(u, v)` lies in a cell that the latest [`Self::foreground`] found in front of the
    /// background; `false` outside the image.
    pub fn in_front(&self, u: usize, v: usize) -> bool {
        let cell_px = self.cell_px as usize;
        let (cu, cv) = (u / cell_px, v / cell_px);
        cu < self.cols as usize
            && cv < self.rows as usize
            && self
                .front
                .get(cv * self.cols as usize + cu)
                .copied()
                .unwrap_or(false)
    }

    /// The cells the latest [`Self::foreground`] found in front of the background (row-major), with the grid's
    /// columns, rows and cell size in depth pixels.
    pub fn front_cells(&self) -> (&[bool], usize, usize, u32) {
        (
            &self.front,
            self.cols as usize,
            self.rows as usize,
            self.cell_px,
        )
    }

    /// Samples per square metre at one metre: divide by `z^2` for the density of samples on a fronto-parallel
    /// surface at depth `z`.
    pub fn samples_per_m2_at_1m(&self, rig: &DepthRig) -> f64 {
        rig.camera.fx * rig.camera.fy / f64::from(self.cell_px * self.cell_px)
    }

    /// Appends to `out` the samples of `frame` nearer than the background by more than `margin(background z)`
    /// metres (or where no background was ever measured), as points in the event camera frame. A sample counts
    /// only if at least two of its four neighbours do too (isolated noise is dropped). Nothing if `frame` does not
    /// match the model's size or `rig`'s camera.
    pub fn foreground(
        &mut self,
        frame: &DepthFrame,
        rig: &DepthRig,
        margin: impl Fn(f64) -> f64,
        out: &mut Vec<Point3<f64>>,
    ) {
        if frame.width != self.width
            || frame.height != self.height
            || frame.width != rig.camera.width
            || frame.height != rig.camera.height
            || frame.depth_m.len() != frame.width as usize * frame.height as usize
        {
            return;
        }
        for cv in 0..self.rows {
            for cu in 0..self.cols {
                let cell = (cv * self.cols + cu) as usize;
                let z = frame.depth_m[self.sample(cu, cv)];
                let far = self.far[cell];
                self.front[cell] = z > 0.0
                    && z.is_finite()
                    && (far <= 0.0 || f64::from(z) < f64::from(far) - margin(f64::from(far)));
            }
        }
        let cam = &rig.camera;
        let half = f64::from(self.cell_px / 2);
        let (cols, rows) = (self.cols as usize, self.rows as usize);
        for cv in 0..rows {
            for cu in 0..cols {
                let cell = cv * cols + cu;
                if !self.front[cell] {
                    continue;
                }
                let neighbours = usize::from(cu > 0 && self.front[cell - 1])
                    + usize::from(cu + 1 < cols && self.front[cell + 1])
                    + usize::from(cv > 0 && self.front[cell - cols])
                    + usize::from(cv + 1 < rows && self.front[cell + cols]);
                if neighbours < 2 {
                    continue;
                }
                let z = f64::from(frame.depth_m[self.sample(cu as u32, cv as u32)]);
                let u = (cu as u32 * self.cell_px) as f64 + half;
                let v = (cv as u32 * self.cell_px) as f64 + half;
                let p = Point3::new((u - cam.cx) / cam.fx * z, (v - cam.cy) / cam.fy * z, z);
                out.push(rig.event_from_depth * p);
            }
        }
    }
}

/// Most seeds tried per search (the foreground is subsampled to this many).
const MAX_SEEDS: usize = 96;

/// An object-sized cluster of foreground points: where a lost object may be.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Cluster {
    /// Foreground points within the search radius of the centre.
    pub support: usize,
    /// Estimated object centre, event camera frame, metres.
    pub centre: Point3<f64>,
    /// Unit direction along which the cluster's points spread most (its principal axis), event camera frame.
    pub axis: Vector3<f64>,
}

/// Finds up to `k` object-sized clusters in `points` (event camera frame): seeds are spread over the points, each
/// is scored by the points within `radius` of it, and the best, at least `radius` apart, are moved to the mean of
/// their neighbourhood by a few mean-shift steps. Each centre is then pushed `depth_offset` metres farther along
/// its viewing ray (the depth camera sees the near side of an object, in front of its centre). Appends to `out`,
/// best first; `seeds` is scratch.
pub(crate) fn cluster_centres(
    points: &[Point3<f64>],
    radius: f64,
    depth_offset: f64,
    k: usize,
    seeds: &mut Vec<(usize, Point3<f64>)>,
    out: &mut Vec<Cluster>,
) {
    seeds.clear();
    if points.is_empty() || k == 0 || radius.is_nan() || radius <= 0.0 {
        return;
    }
    let r2 = radius * radius;
    let within = |c: &Point3<f64>| {
        points
            .iter()
            .filter(|p| (*p - c).norm_squared() <= r2)
            .count()
    };
    let step = points.len().div_ceil(MAX_SEEDS).max(1);
    for p in points.iter().step_by(step) {
        if seeds.len() >= MAX_SEEDS {
            break;
        }
        seeds.push((within(p), *p));
    }
    // Stable (ties keep the seeds' order); 96 seeds fit the sort's stack scratch, so nothing is allocated.
    seeds.sort_by_key(|s| std::cmp::Reverse(s.0));
    let first = out.len();
    for &(_, seed) in seeds.iter() {
        if out.len() - first >= k {
            break;
        }
        let mut c = seed;
        let mut support = 0;
        let mut scatter = Matrix3::zeros();
        for _ in 0..4 {
            let mut sum = Vector3::zeros();
            let mut outer = Matrix3::zeros();
            let mut n = 0usize;
            for p in points {
                let d = p - c;
                if d.norm_squared() <= r2 {
                    sum += p.coords;
                    outer += d * d.transpose();
                    n += 1;
                }
            }
            if n == 0 {
                break;
            }
            let mean = sum / n as f64;
            // Scatter about the new mean from the scatter about the old centre.
            let shift = mean - c.coords;
            scatter = outer / n as f64 - shift * shift.transpose();
            c = Point3::from(mean);
            support = n;
        }
        if support == 0 || out[first..].iter().any(|o| (o.centre - c).norm() < radius) {
            continue;
        }
        let eigen = SymmetricEigen::new(scatter);
        let largest = eigen.eigenvalues.imax();
        let axis = eigen.eigenvectors.column(largest).normalize();
        let ray = c.coords.normalize();
        out.push(Cluster {
            support,
            centre: c + ray * depth_offset,
            axis,
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Isometry3;
    use scene::geometry::PinholeCamera;

    fn rig() -> DepthRig {
        DepthRig {
            camera: PinholeCamera::new(425.0, 425.0, 423.5, 239.5, 848, 480).unwrap(),
            event_from_depth: Isometry3::translation(0.06, 0.0, 0.0),
        }
    }

    fn frame(z: impl Fn(u32, u32) -> f32) -> DepthFrame {
        let (w, h) = (848, 480);
        DepthFrame {
            index: 0,
            width: w,
            height: h,
            depth_m: (0..h)
                .flat_map(|v| (0..w).map(move |u| (u, v)))
                .map(|(u, v)| z(u, v))
                .collect(),
        }
    }

    /// A wall at 2 m with a 60 x 60 pixel box at 0.6 m centred on `(u0, v0)`.
    /// ... and a shelf that never moves: a 40 x 40 pixel box at 1 m centred on (700, 400).
    fn scene(u0: u32, v0: u32) -> DepthFrame {
        frame(move |u, v| {
            if u.abs_diff(u0) < 30 && v.abs_diff(v0) < 30 {
                0.6
            } else if u.abs_diff(700) < 20 && v.abs_diff(400) < 20 {
                1.0
            } else {
                2.0
            }
        })
    }

    #[test]
    fn background_learns_the_wall_and_foreground_finds_the_moved_box() {
        let rig = rig();
        let mut bg = DepthBackground::new(4, 848, 480);
        // The box starts at the left and moves right: its first place is revealed as wall.
        bg.update(&scene(200, 240));
        bg.update(&scene(600, 240));
        let mut fg = Vec::with_capacity(10_000);
        bg.foreground(&scene(200, 240), &rig, |_| 0.05, &mut fg);
        assert!(
            fg.len() > 150 && fg.len() < 260,
            "{} foreground samples",
            fg.len()
        );
        let mut seeds = Vec::with_capacity(MAX_SEEDS);
        let mut centres = Vec::with_capacity(4);
        cluster_centres(&fg, 0.05, 0.0, 3, &mut seeds, &mut centres);
        assert_eq!(centres.len(), 1, "{centres:?}");
        // The box's centre pixel (200, 240) at 0.6 m, in the event camera frame.
        let expected = rig.event_from_depth
            * rig
                .camera
                .unproject(&nalgebra::Point2::new(200.0, 240.0), 0.6);
        assert!(
            (centres[0].centre - expected).norm() < 0.01,
            "{:?} vs {expected:?}",
            centres[0]
        );
        // A few isolated noisy samples in front of the wall are not foreground.
        fg.clear();
        let noisy = frame(|u, v| {
            if (u % 40 == 2) && (v % 40 == 2) {
                1.0
            } else {
                2.0
            }
        });
        bg.foreground(&noisy, &rig, |_| 0.05, &mut fg);
        assert!(fg.is_empty(), "{} samples", fg.len());
        // The shelf, there in every frame so far, is background: in a frame with the box back where it was
        // last seen, only the box is foreground.
        fg.clear();
        bg.foreground(&scene(600, 240), &rig, |_| 0.05, &mut fg);
        let box_centre = rig.event_from_depth
            * rig
                .camera
                .unproject(&nalgebra::Point2::new(600.0, 240.0), 0.6);
        assert!(!fg.is_empty());
        assert!(
            fg.iter().all(|p| (p - box_centre).norm() < 0.1),
            "shelf in the foreground"
        );
    }

    #[test]
    fn two_clusters_are_found_best_first_and_pushed_along_the_ray() {
        // A 10 x 10 patch at x = -0.2 and, after it, a 6 x 10 patch at x = +0.2 (5 mm pitch).
        let patch = |x0: f64, z: f64, columns: u32| {
            (0..columns).flat_map(move |i| {
                (0..10)
                    .map(move |j| Point3::new(x0 + f64::from(i) * 0.005, f64::from(j) * 0.005, z))
            })
        };
        let points: Vec<_> = patch(-0.2, 0.6, 10).chain(patch(0.2, 0.7, 6)).collect();
        let mut seeds = Vec::with_capacity(MAX_SEEDS);
        let mut out = Vec::with_capacity(4);
        cluster_centres(&points, 0.06, 0.02, 3, &mut seeds, &mut out);
        assert_eq!(out.len(), 2, "{out:?}");
        assert!(out[0].support > out[1].support);
        let plain = Point3::new(-0.2 + 0.0225, 0.0225, 0.6);
        let pushed = plain + plain.coords.normalize() * 0.02;
        assert!((out[0].centre - pushed).norm() < 1e-9, "{:?}", out[0]);
        assert!(out[1].centre.x > 0.2);
        // The second patch is 6 x 10 samples: longer along y.
        assert!(out[1].axis.y.abs() > 0.99, "{:?}", out[1].axis);
    }

    #[test]
    fn a_thin_rod_in_any_direction_gives_its_direction_as_axis() {
        let mut seeds = Vec::with_capacity(MAX_SEEDS);
        let mut out = Vec::with_capacity(1);
        for dir in [
            Vector3::new(1.0, 1.0, 0.0),
            Vector3::new(0.0, 1.0, 2.0),
            Vector3::new(-1.0, 0.2, 0.4),
        ] {
            let dir = dir.normalize();
            let side = dir
                .cross(&Vector3::z())
                .try_normalize(1e-9)
                .unwrap_or(Vector3::x());
            let points: Vec<_> = (0..60)
                .flat_map(|i| {
                    (0..3).map(move |j| {
                        Point3::new(0.0, 0.0, 0.6)
                            + dir * (f64::from(i) * 0.002 - 0.06)
                            + side * (f64::from(j) * 0.003)
                    })
                })
                .collect();
            out.clear();
            cluster_centres(&points, 0.07, 0.0, 1, &mut seeds, &mut out);
            assert_eq!(out.len(), 1);
            assert!(
                out[0].axis.dot(&dir).abs() > 0.99,
                "{:?} vs {dir:?}",
                out[0].axis
            );
        }
    }

    #[test]
    fn mismatched_or_empty_input_gives_nothing() {
        let rig = rig();
        let mut bg = DepthBackground::new(4, 848, 480);
        let small = DepthFrame {
            index: 0,
            width: 10,
            height: 10,
            depth_m: vec![0.5; 100],
        };
        let mut fg = Vec::with_capacity(100);
        bg.foreground(&small, &rig, |_| 0.05, &mut fg);
        assert!(fg.is_empty());
        // A frame whose buffer is shorter than its size is ignored rather than indexed out of bounds.
        bg.update(&DepthFrame {
            index: 0,
            width: 848,
            height: 480,
            depth_m: vec![1.0; 10],
        });
        let mut seeds = Vec::with_capacity(MAX_SEEDS);
        let mut out = Vec::with_capacity(4);
        cluster_centres(&[], 0.05, 0.0, 3, &mut seeds, &mut out);
        assert!(out.is_empty());
        cluster_centres(
            &[Point3::new(0.0, 0.0, 1.0)],
            f64::NAN,
            0.0,
            3,
            &mut seeds,
            &mut out,
        );
        assert!(out.is_empty());
    }
}

//! Pose error functions after the BOP toolkit's `pose_error.py`: ADD, ADD-S, MSSD and MSPD.
//!
//! Poses are `T_cam_obj` (object frame to camera frame, metres); model points are in the object frame, metres.

use super::kdtree::KdTree;
use nalgebra::{Isometry3, Point2, Point3};
use scene::geometry::PinholeCamera;

/// ADD (Hinterstoisser et al.; BOP `add`): mean distance between the model points under the estimated and the
/// ground-truth pose, metres.
pub fn add(est: &Isometry3<f64>, gt: &Isometry3<f64>, points: &[Point3<f64>]) -> f64 {
    if points.is_empty() {
        return f64::INFINITY;
    }
    let sum: f64 = points.iter().map(|p| (est * p - gt * p).norm()).sum();
    sum / points.len() as f64
}

/// ADD-S (BOP `adi`): mean over the ground-truth-posed points of the distance to the nearest estimated-posed
/// point, metres. Builds a k-d tree over the estimated points.
pub fn add_s(est: &Isometry3<f64>, gt: &Isometry3<f64>, points: &[Point3<f64>]) -> f64 {
    if points.is_empty() {
        return f64::INFINITY;
    }
    let est_pts: Vec<Point3<f64>> = points.iter().map(|p| est * p).collect();
    let tree = KdTree::new(&est_pts);
    let sum: f64 = points
        .iter()
        .map(|p| tree.nearest_distance(&(gt * p)))
        .sum();
    sum / points.len() as f64
}

/// MSSD (BOP `mssd`): the minimum over symmetry transforms `S` of the maximum distance between the model points
/// under the estimate and under `gt * S`, metres. `symmetries` includes the identity (see
/// [`super::symmetry_transforms`]).
pub fn mssd(
    est: &Isometry3<f64>,
    gt: &Isometry3<f64>,
    points: &[Point3<f64>],
    symmetries: &[Isometry3<f64>],
) -> f64 {
    let est_pts: Vec<Point3<f64>> = points.iter().map(|p| est * p).collect();
    symmetries
        .iter()
        .map(|s| {
            let g = gt * s;
            est_pts
                .iter()
                .zip(points)
                .map(|(e, p)| (e - g * p).norm())
                .fold(0.0, f64::max)
        })
        .fold(f64::INFINITY, f64::min)
}

/// MSPD (BOP `mspd`): the minimum over symmetry transforms of the maximum distance between the projections of the
/// model points under the estimate and under `gt * S`, pixels of `camera` (unscaled; the 640 / width
/// normalisation is applied when scoring). Points are projected with the pinhole model without a z check, as BOP.
pub fn mspd(
    est: &Isometry3<f64>,
    gt: &Isometry3<f64>,
    camera: &PinholeCamera,
    points: &[Point3<f64>],
    symmetries: &[Isometry3<f64>],
) -> f64 {
    let est_px: Vec<Point2<f64>> = points.iter().map(|p| project(camera, &(est * p))).collect();
    symmetries
        .iter()
        .map(|s| {
            let g = gt * s;
            est_px
                .iter()
                .zip(points)
                .map(|(e, p)| (e - project(camera, &(g * p))).norm())
                .fold(0.0, f64::max)
        })
        .fold(f64::INFINITY, f64::min)
}

/// Pinhole projection `K p / z` (BOP `misc.project_pts`), pixels.
fn project(camera: &PinholeCamera, p: &Point3<f64>) -> Point2<f64> {
    Point2::new(
        camera.fx * p.x / p.z + camera.cx,
        camera.fy * p.y / p.z + camera.cy,
    )
}

//! At a fresh depth frame, the refinement's start moved along its line of sight onto the measured surface. The
//! events barely see an object move along the line of sight, so an object approaching at 2.5 m/s is 8 cm nearer
//! than the estimate by the first depth frame after its first pose, before the depth frames have measured its
//! range's rate; the depth term reaches only `max_residual` (3 cm) and takes a measurement nearer than the model by
//! more than `occlusion_gap` (2.5 cm) for an occluder, so it cannot pull the estimate there by itself.

use super::model::ObjectModel;
use crate::recon::DepthImage;
use crate::refine::ModelView;
use crate::track::config::TrackerConfig;
use nalgebra::{Isometry3, Point3, Translation3};
use scene::geometry::PinholeCamera;

/// Share of the surface samples with a measurement whose offset must agree with the median one: a hand in front
/// of part of the object offsets only that part.
const MIN_AGREEING_SHARE: f64 = 0.7;

/// Share of the visible surface samples that must have a measurement at all.
const MIN_MEASURED_SHARE: f64 = 0.5;

/// `pose` moved along the line of sight to the object's centre by the median offset between the depth `depth`
/// (the ROI camera `camera`'s image) measures and the depth of `view`'s surface samples at `pose`, when that offset
/// is beyond half the depth term's `occlusion_gap` (nearer offsets the refinement handles), within the object's
/// diameter, and agreed (within 1 cm plus two noise sigmas) by at least [`MIN_AGREEING_SHARE`] of the samples
/// measured, which are at least [`MIN_MEASURED_SHARE`] of them. `None` otherwise. `offsets` is scratch.
pub(super) fn aligned_range(
    model: &ObjectModel,
    view: &ModelView,
    pose: &Isometry3<f64>,
    camera: &PinholeCamera,
    depth: &DepthImage,
    config: &TrackerConfig,
    offsets: &mut Vec<f64>,
) -> Option<Isometry3<f64>> {
    offsets.clear();
    let mut measured = 0usize;
    for sp in &view.surface {
        let p = pose * sp.position;
        if p.z <= 0.01 {
            continue;
        }
        let u = (camera.fx * p.x / p.z + camera.cx).round() as i32;
        let v = (camera.fy * p.y / p.z + camera.cy).round() as i32;
        let zm = f64::from(depth.at(u, v));
        if !(zm > 0.0 && zm.is_finite()) {
            continue;
        }
        measured += 1;
        let offset = zm - p.z;
        if offset.abs() <= model.diameter {
            offsets.push(offset);
        }
    }
    if offsets.is_empty() || (measured as f64) < MIN_MEASURED_SHARE * view.surface.len() as f64 {
        return None;
    }
    let mid = offsets.len() / 2;
    let median = *offsets.select_nth_unstable_by(mid, |a, b| a.total_cmp(b)).1;
    if median.abs() <= 0.5 * config.depth_term.occlusion_gap {
        return None;
    }
    let centre = pose * Point3::from(model.center_obj);
    let noise = &config.depth_term;
    let agree = 0.01 + 2.0 * (noise.sigma_0 + noise.sigma_z2 * centre.z * centre.z);
    let agreeing = offsets
        .iter()
        .filter(|o| (*o - median).abs() <= agree)
        .count();
    if (agreeing as f64) < MIN_AGREEING_SHARE * measured as f64 {
        return None;
    }
    let ray = centre.coords.normalize();
    (ray.z > 1e-6).then(|| Translation3::from(ray * (median / ray.z)) * pose)
}

//! Depth-only checks of a pose hypothesis against the latest depth image: the agreeing fraction of model points,
//! a depth-only refinement, the re-detection probe and the silhouette agreement.

use super::carried_depth::carry_depth_from;
use super::inputs::TickInputs;
use super::model::ObjectModel;
use super::motion::anchored_extrapolation;
use super::optimise::optimiser;
use super::scratch::TickScratch;
use super::state::ObjectState;
use crate::recon::DepthImage;
use crate::refine::{DepthModality, DepthTermStats, ModelView, apply_step};
use crate::track::config::TrackerConfig;
use crate::track::fallback_check::{FALLBACK_STARTS, FallbackStart};
use nalgebra::Isometry3;
use scene::geometry::PinholeCamera;

/// The depth term's counts for the model's visible points at `pose` against `D_t` (`scratch.depth_now`).
pub(super) fn depth_stats_at(
    scratch: &TickScratch,
    pose: &Isometry3<f64>,
    roi_camera: &PinholeCamera,
    config: &TrackerConfig,
) -> DepthTermStats {
    config
        .depth_term
        .stats(&scratch.view, pose, roi_camera, &scratch.depth_now)
}

/// How well this tick's depth frame confirms the motion from the previous depth frame's estimate to `pose`
/// ([`crate::recon::MovingNeighbourhood::motion_agreement`]); `None` without a depth frame or kept surfaces.
pub(super) fn motion_agreement_at(
    state: &ObjectState,
    pose: &Isometry3<f64>,
    inputs: &TickInputs<'_>,
    config: &TrackerConfig,
) -> Option<f64> {
    // The frame shows the object at its exposure: a late frame's is the hypothesis carried back there.
    let at_exposure = match state.late_motion {
        Some((_, motion)) => motion.inverse() * pose,
        None => *pose,
    };
    motion_agreement_at_exposure(state, &at_exposure, inputs, config)
}

/// [`motion_agreement_at`] for `pose`, the object's pose at the depth frame's exposure.
pub(super) fn motion_agreement_at_exposure(
    state: &ObjectState,
    pose: &Isometry3<f64>,
    inputs: &TickInputs<'_>,
    config: &TrackerConfig,
) -> Option<f64> {
    let frame = inputs.depth?;
    if state.neighbourhood.is_empty() {
        return None;
    }
    state.neighbourhood.motion_agreement(
        pose,
        frame,
        inputs.depth_rig,
        config.depth_term.occlusion_gap as f32,
    )
}

/// Where the depth safety net's candidates for the pose at `t_us` start, in [`FallbackStart`] order: the pose
/// `anchor` of the previous depth frame (exposed at `t_anchor`, microseconds) and, as configured, that pose
/// carried on to `t_us` at the tracker's velocity and at the motion between the two depth frames before. None
/// of them depends on what the events did since `t_anchor`.
pub(super) fn fallback_starts(
    model: &ObjectModel,
    state: &ObjectState,
    t_anchor: i64,
    anchor: &Isometry3<f64>,
    t_us: i64,
    config: &TrackerConfig,
) -> [Option<(FallbackStart, Isometry3<f64>)>; FALLBACK_STARTS] {
    let span = (t_us - t_anchor).max(0) as f64 * 1e-6;
    [
        Some((FallbackStart::PreviousDepthPose, *anchor)),
        config.safety_net.depth_fallback_extrapolate.then(|| {
            let start = apply_step(anchor, &model.center_obj, &(state.velocity * span));
            (FallbackStart::Extrapolated, start)
        }),
        config
            .safety_net
            .depth_fallback_anchored
            .then(|| anchored_extrapolation(model, state, t_us, config))
            .flatten()
            .map(|start| (FallbackStart::AnchoredMotion, start)),
    ]
}

/// Depth-only refinement from `start` against `D_t` (what `depth30` does at a depth frame): the refined pose and
/// the depth term's counts there.
pub(super) fn refine_on_depth(
    model: &ObjectModel,
    scratch: &TickScratch,
    start: Isometry3<f64>,
    roi_camera: &PinholeCamera,
    config: &TrackerConfig,
) -> (Isometry3<f64>, DepthTermStats) {
    refine_on_depth_in(
        model,
        &scratch.view,
        start,
        roi_camera,
        &scratch.depth_now,
        config,
    )
}

/// [`refine_on_depth`] of `view` against `depth`, an image in `camera`.
pub(super) fn refine_on_depth_in(
    model: &ObjectModel,
    view: &ModelView,
    start: Isometry3<f64>,
    camera: &PinholeCamera,
    depth: &DepthImage,
    config: &TrackerConfig,
) -> (Isometry3<f64>, DepthTermStats) {
    let mut modality = DepthModality {
        active: true,
        term: &config.depth_term,
        camera,
        depth,
        weight: 1.0,
        stats: None,
    };
    let pose =
        optimiser(model, config, None).run(&mut [&mut modality], view, &model.center_obj, start);
    let stats = config.depth_term.stats(view, &pose, camera, depth);
    (pose, stats)
}

/// Checks the hypothesis `state.predicted` against the fresh depth frame of `inputs` (re-detection): registers
/// the frame around it and refines on depth only from it, using the render the caller made at it in
/// `scratch.target`. Returns the agreeing fraction of the model points left in view ([`seen_agreement`]) and the
/// refined pose; `None` without a depth frame, ROI or visible model.
pub(super) fn probe_depth(
    model: &ObjectModel,
    state: &mut ObjectState,
    scratch: &mut TickScratch,
    inputs: &TickInputs<'_>,
    config: &TrackerConfig,
) -> Option<(f64, Isometry3<f64>)> {
    let roi = state.roi?;
    let frame = inputs.depth?;
    let roi_camera = inputs.camera.crop(&roi);
    let start = state.predicted;
    scratch.view.extract(
        &scratch.target,
        &roi_camera,
        model.label,
        &start,
        config.correspond.max_surface_points,
        config.correspond.max_contour_points,
    );
    if scratch.view.surface.is_empty() {
        return None;
    }
    carry_depth_from(model, state, frame, inputs.depth_rig, inputs.t_us, config);
    state
        .carried
        .render(&start, &roi_camera, &mut scratch.depth_now);
    let (pose, stats) = refine_on_depth(model, scratch, start, &roi_camera, config);
    Some((seen_agreement(&stats), pose))
}

/// How well the silhouette in `scratch.target` (rendered at `pose`) matches what the fresh depth image in
/// `scratch.depth_now` shows at the object's depth ([`silhouette_overlap`]). Re-detection ranks places by it:
/// unlike the agreeing fraction of model points, it stays low for a pose that shows only a small part of the
/// object where the depth sees all of it.
pub(super) fn silhouette_agreement(
    model: &ObjectModel,
    scratch: &TickScratch,
    pose: &Isometry3<f64>,
    config: &TrackerConfig,
) -> f64 {
    let c = model.center_at(pose);
    let noise = config.depth_term;
    silhouette_overlap(
        &scratch.depth_now.z,
        scratch.target.depth(),
        scratch.target.mask(),
        model.label,
        c.z,
        0.5 * model.diameter,
        3.0 * (noise.sigma_0 + noise.sigma_z2 * c.z * c.z) + 0.005,
    )
}

/// Below this fraction of its model points in view, a re-detection place is scored as if this fraction were in
/// view: a place hidden behind an occluder must not win on the few points left.
const MIN_SEEN_FRACTION: f64 = 0.3;

/// The fraction of a pose's model points the depth confirms, among those not hidden by a nearer measurement (at
/// least [`MIN_SEEN_FRACTION`] of all); re-detection ranks places by it and the safety net compares the estimate
/// with its candidates by it. A hand or another object in front of part of the object is neither for nor against
/// the pose: counting its points as disagreeing scored a correctly placed, half-hidden object below the hand
/// holding it, which re-detection then took for the object (and the safety net kept a drifting estimate over a
/// correct candidate).
pub(super) fn seen_agreement(stats: &DepthTermStats) -> f64 {
    let all = stats.points as f64;
    let seen = (stats.points.saturating_sub(stats.occluded) as f64).max(MIN_SEEN_FRACTION * all);
    if seen <= 0.0 {
        return 0.0;
    }
    (stats.inliers as f64 / seen).min(1.0)
}

/// Of two depth terms' counts, those that agree less ([`seen_agreement`]; the first on a tie); either when the
/// other is unknown.
pub(super) fn weaker_fit(
    a: Option<DepthTermStats>,
    b: Option<DepthTermStats>,
) -> Option<DepthTermStats> {
    match (a, b) {
        (Some(a), Some(b)) if seen_agreement(&b) < seen_agreement(&a) => Some(b),
        (a, b) => a.or(b),
    }
}

/// Intersection over union of a rendered silhouette with the measured depth near the object, in [0, 1]: pixels
/// where the model (`mask == label`) and the measurement (`measured`, metres, 0 = invalid) agree within
/// `tolerance` metres, over pixels where either the model is or a measurement lies within `band` metres of the
/// object centre's depth `centre_z`. Model pixels whose measurement is nearer than the model by more than
/// `tolerance` are hidden by an occluder and left out of both. The three slices are row-major over one ROI.
pub(super) fn silhouette_overlap(
    measured: &[f32],
    rendered: &[f32],
    mask: &[u16],
    label: u16,
    centre_z: f64,
    band: f64,
    tolerance: f64,
) -> f64 {
    let (mut agree, mut union) = (0usize, 0usize);
    for (&zm, (&zr, &l)) in measured.iter().zip(rendered.iter().zip(mask)) {
        let model = l == label;
        if model && zm > 0.0 && f64::from(zr - zm) > tolerance {
            continue;
        }
        let near = zm > 0.0 && (f64::from(zm) - centre_z).abs() < band;
        union += usize::from(model || near);
        agree += usize::from(model && zm > 0.0 && f64::from((zm - zr).abs()) < tolerance);
    }
    agree as f64 / union.max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stats(points: usize, occluded: usize, inliers: usize) -> DepthTermStats {
        DepthTermStats {
            points,
            measured: points - occluded,
            occluded,
            inliers,
        }
    }

    #[test]
    fn hidden_points_count_neither_for_nor_against_a_place() {
        // Nothing hidden: the plain agreeing fraction.
        assert!((seen_agreement(&stats(200, 0, 150)) - 0.75).abs() < 1e-12);
        // Half hidden by a hand, the rest agreeing: as good as a fully seen, fully agreeing place.
        assert!((seen_agreement(&stats(200, 100, 100)) - 1.0).abs() < 1e-12);
        // Almost all hidden: scored as if 30 % were seen, so 10 agreeing points stay a poor place.
        assert!((seen_agreement(&stats(200, 190, 10)) - 10.0 / 60.0).abs() < 1e-12);
        assert_eq!(seen_agreement(&stats(0, 0, 0)), 0.0);
    }

    #[test]
    fn the_weaker_fit_is_the_less_agreeing_one_or_the_known_one() {
        let (good, poor) = (stats(200, 0, 180), stats(200, 100, 40));
        assert_eq!(weaker_fit(Some(good), Some(poor)), Some(poor));
        assert_eq!(weaker_fit(Some(poor), Some(good)), Some(poor));
        assert_eq!(weaker_fit(None, Some(good)), Some(good));
        assert_eq!(weaker_fit(Some(poor), None), Some(poor));
        assert_eq!(weaker_fit(None, None), None);
        // On a tie, the first: 150 of 200 seen against 75 of 100 seen (100 hidden).
        let (a, b) = (stats(200, 0, 150), stats(200, 100, 75));
        assert_eq!(weaker_fit(Some(a), Some(b)), Some(a));
    }

    #[test]
    fn silhouette_leaves_out_model_pixels_behind_an_occluder() {
        // A 10-pixel row: the model covers pixels 0..8 at 0.60 m; the depth agrees on 0..4, a hand at 0.55 m
        // covers 4..8 and also pixels 8..10 beside the object (within half a diameter of its depth).
        let label = 3;
        let rendered = [0.6f32; 10];
        let mask: Vec<u16> = (0..10).map(|i| if i < 8 { label } else { 0 }).collect();
        let measured: Vec<f32> = (0..10).map(|i| if i < 4 { 0.6 } else { 0.55 }).collect();
        let iou = silhouette_overlap(&measured, &rendered, &mask, label, 0.6, 0.05, 0.01);
        // Agreeing 4 over the seen model (4) and the hand beside it (2).
        assert!((iou - 4.0 / 6.0).abs() < 1e-12, "{iou}");
        // The same hand behind the model instead (measured farther) is evidence against it.
        let behind: Vec<f32> = (0..10).map(|i| if i < 4 { 0.6 } else { 0.63 }).collect();
        let iou = silhouette_overlap(&behind, &rendered, &mask, label, 0.6, 0.05, 0.01);
        assert!((iou - 4.0 / 10.0).abs() < 1e-12, "{iou}");
    }
}

//! One tracked object's state and its per-tick refinement.

use super::config::{DepthUse, TrackerConfig};
use super::estimate::TrackingState;
use crate::geometry::{PinholeCamera, Roi};
use crate::recon::{CarriedDepth, DepthImage, DepthRig, EventSurface};
use crate::refine::{
    DepthTermStats, EventEdges, EventTermKind, IntensityEdges, ModelView, NormalEquations,
    StepBounds, apply_step, solve_step,
};
use crate::render::RenderTarget;
use drivers::recording::DepthFrame;
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3, Vector6};

/// A tracked object: its model, its state and the buffers its refinement reuses every tick.
#[derive(Debug)]
pub(crate) struct ObjectTrack {
    pub label: u16,
    pub diameter: f64,
    pub center_obj: Vector3<f64>,
    pub aabb_min: Vector3<f64>,
    pub aabb_max: Vector3<f64>,
    /// Latest estimate and its time.
    pub pose: Isometry3<f64>,
    pub t_us: i64,
    /// Estimate before the latest, for interpolation.
    pub previous: Option<(i64, Isometry3<f64>)>,
    /// Smoothed velocity of the centre (m/s) and angular velocity (rad/s), camera frame.
    pub velocity: Vector6<f64>,
    pub predicted: Isometry3<f64>,
    /// The estimate at the latest fresh depth frame (time, pose).
    anchor: Option<(i64, Isometry3<f64>)>,
    pub quality: f32,
    pub state: TrackingState,
    low_ticks: u32,
    /// Depth frames at which the depth-only hypothesis replaced the event-driven estimate.
    pub fallbacks: u64,
    /// Depth frames at which re-detection moved the object.
    pub redetections: u64,
    depth_fit: f64,
    depth_frames_used: u32,
    pub roi: Option<Roi>,
    pub target: RenderTarget,
    view: ModelView,
    carried: CarriedDepth,
    depth_now: DepthImage,
    edges: EventEdges,
    intensity_edges: IntensityEdges,
}

/// Per-tick inputs shared by every object.
pub(crate) struct TickInputs<'a> {
    pub t_us: i64,
    pub dt_s: f64,
    pub depth: Option<&'a DepthFrame>,
    pub surface: &'a EventSurface,
    pub camera: &'a PinholeCamera,
    pub depth_rig: &'a DepthRig,
}

impl ObjectTrack {
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        label: u16,
        diameter: f64,
        aabb_min: Vector3<f64>,
        aabb_max: Vector3<f64>,
        pose: Isometry3<f64>,
        t_us: i64,
        config: &TrackerConfig,
    ) -> Self {
        let n = config.roi_size as usize;
        Self {
            label,
            diameter,
            center_obj: (aabb_min + aabb_max) * 0.5,
            aabb_min,
            aabb_max,
            pose,
            t_us,
            previous: None,
            velocity: Vector6::zeros(),
            predicted: pose,
            anchor: None,
            quality: 1.0,
            state: TrackingState::Tracking,
            low_ticks: 0,
            fallbacks: 0,
            redetections: 0,
            depth_fit: 1.0,
            depth_frames_used: 0,
            roi: None,
            target: RenderTarget::with_capacity(config.roi_size, config.roi_size),
            view: ModelView::with_capacity(config.max_surface_points, config.max_contour_points),
            carried: CarriedDepth::new(),
            depth_now: DepthImage {
                width: config.roi_size,
                height: config.roi_size,
                z: Vec::with_capacity(n * n),
            },
            edges: EventEdges::default(),
            intensity_edges: IntensityEdges::default(),
        }
    }

    /// The object's centre in the camera frame at `pose`.
    pub fn center_at(&self, pose: &Isometry3<f64>) -> Point3<f64> {
        pose * Point3::from(self.center_obj)
    }

    /// Predicts the pose `dt_s` after the latest estimate (constant velocity about the centre).
    pub fn predict(&mut self, dt_s: f64, config: &TrackerConfig) {
        self.predicted = if config.prediction && self.state != TrackingState::Lost {
            let mut xi = self.velocity * (dt_s * config.prediction_gain);
            if !config.predict_rotation {
                xi.fixed_rows_mut::<3>(3).fill(0.0);
            }
            apply_step(&self.pose, &self.center_obj, &xi)
        } else {
            self.pose
        };
    }

    /// The ROI around the predicted pose, if the object is in front of the camera. At a depth exposure
    /// (`depth_due`) with the extrapolated depth fallback on, it is widened to also hold the object where the
    /// previous depth pose carried on at the measured velocity puts it, so the depth image covers that start too.
    pub fn update_roi(
        &mut self,
        camera: &PinholeCamera,
        config: &TrackerConfig,
        t_us: i64,
        depth_due: bool,
    ) -> Option<Roi> {
        let mut c = self.center_at(&self.predicted);
        let mut scale = config.roi_scale;
        if depth_due
            && config.depth_fallback_extrapolate
            && config.depth_fallback_margin >= 0.0
            && config.roi_widen_at_depth
            && let Some((t_anchor, anchor)) = self.anchor
        {
            let span = (t_us - t_anchor).max(0) as f64 * 1e-6;
            let start = apply_step(&anchor, &self.center_obj, &(self.velocity * span));
            let other = self.center_at(&start);
            let gap = (other - c).norm();
            if gap.is_finite() && gap > 0.1 * self.diameter {
                c = Point3::from((c.coords + other.coords) * 0.5);
                scale += gap / self.diameter;
            }
        }
        // Behind the camera: no ROI (checked here so the lost path does not build an error message per tick).
        if !(c.z > 1e-3 && c.coords.iter().all(|v| v.is_finite())) {
            self.roi = None;
            return None;
        }
        self.roi = Roi::around_object(camera, &c, self.diameter, scale, config.roi_size).ok();
        self.roi
    }

    /// Image speed of the object's outline predicted from the velocity, full-image pixels per second.
    fn image_speed(&self, camera: &PinholeCamera) -> f64 {
        let c = self.center_at(&self.predicted);
        let z = c.z.max(0.05);
        let v = self.velocity;
        let lateral = (v[0] * v[0] + v[1] * v[1]).sqrt() + (v[2].abs() * self.diameter * 0.5 / z);
        let angular = Vector3::new(v[3], v[4], v[5]).norm() * self.diameter * 0.5;
        camera.fx * (lateral + angular) / z
    }

    /// Refines the predicted pose at this tick from the render already in `self.target` (made at the predicted
    /// poses of all objects) and updates quality, state and velocity.
    pub fn refine(&mut self, inputs: &TickInputs<'_>, config: &TrackerConfig) {
        let Some(roi) = self.roi else {
            self.finish(inputs, self.predicted, None, None, config);
            return;
        };
        let roi_camera = inputs.camera.crop(&roi);
        let predicted = self.predicted;
        self.view.extract(
            &self.target,
            &roi_camera,
            self.label,
            &predicted,
            config.max_surface_points,
            config.max_contour_points,
        );

        // Depth: which D_t is available at this tick, and its weight.
        let fresh = inputs.depth.is_some()
            && match config.depth {
                DepthUse::EveryTick | DepthUse::DepthFramesOnly => true,
                DepthUse::FirstFrameOnly => self.depth_frames_used == 0,
                DepthUse::Off => false,
            };
        let mut depth_weight = 0.0;
        if fresh {
            if let Some(frame) = inputs.depth {
                let c = self.center_at(&predicted);
                let radius = 0.6 * config.roi_scale * self.diameter + 0.08;
                self.carried
                    .register(frame, inputs.depth_rig, &c, radius, inputs.t_us);
                self.carried
                    .render(&predicted, &roi_camera, &mut self.depth_now);
                depth_weight = 1.0;
            }
        } else if config.depth == DepthUse::EveryTick && !self.carried.is_empty() {
            // Rendered below, at the pose the refinement starts from.
            depth_weight = config.carried_depth_weight;
        }
        let refine_now = match config.depth {
            DepthUse::DepthFramesOnly => fresh,
            _ => true,
        };
        if !refine_now {
            self.finish(inputs, self.pose, None, None, config);
            return;
        }

        let depth_term = config.depth_term;
        let event_term = config.event_term;
        let use_events = config.events && !self.view.contour.is_empty();
        let intensity_term = config.intensity_term;
        let use_intensity = use_events && intensity_term.weight > 0.0;
        let contrast_max = use_events && event_term.kind == EventTermKind::ContrastMax;
        let use_event_residuals = use_events && !contrast_max;
        let mut contrast_velocity = None;
        let mut window_s = 0.0;
        if use_events {
            let speed = self.image_speed(inputs.camera).max(1.0);
            let window = ((config.event_window_px / speed) * 1e6) as i64;
            let window = window.clamp(config.min_event_window_us, config.max_event_window_us);
            window_s = window as f64 * 1e-6;
            self.edges.collect(
                &event_term,
                inputs.surface,
                &roi,
                self.target.mask(),
                self.label,
                inputs.t_us,
                window,
                config.max_event_points,
            );
            if contrast_max {
                let c = self.center_at(&predicted);
                self.edges.lift_events(
                    inputs.surface,
                    inputs.camera,
                    self.target.depth(),
                    self.target.mask(),
                    self.label,
                    inputs.t_us,
                    window,
                    c.z,
                    config.max_event_points * 8,
                );
                contrast_velocity = Some(self.edges.maximise_contrast(
                    inputs.camera,
                    &c,
                    &self.velocity,
                    event_term.contrast_step_translation,
                    event_term.contrast_step_rotation,
                    event_term.contrast_rounds,
                ));
            }
        }
        let bounds = StepBounds {
            max_rotation: config.max_step_rotation_deg.to_radians(),
            max_translation: config.max_step_translation_diameters * self.diameter,
        };
        let mut pose = match contrast_velocity {
            // The motion contrast maximisation found, from the previous estimate.
            Some(xi) => {
                let span = (inputs.t_us - self.t_us).max(0) as f64 * 1e-6;
                apply_step(&self.pose, &self.center_obj, &(xi * span))
            }
            None => predicted,
        };
        // Until two depth frames have measured the motion, and while the estimate is not trusted, the whole
        // range is searched.
        let search_range = if self.depth_frames_used < 2
            || (config.search_wide_when_degraded && self.state != TrackingState::Tracking)
        {
            event_term.search_px
        } else {
            // max-then-min rather than clamp: a config with min > max must not panic (the range is then max).
            (event_term.search_speed_factor * self.image_speed(inputs.camera) * inputs.dt_s)
                .max(event_term.search_min_px)
                .min(event_term.search_px)
        };
        if use_event_residuals
            && let Some([du, dv]) = self.edges.search_shift(
                &event_term,
                &self.view,
                &predicted,
                inputs.camera,
                search_range,
            )
        {
            // Move the centre laterally by the image shift at its depth.
            let c = self.center_at(&predicted);
            let shift = Vector3::new(
                du * c.z / inputs.camera.fx,
                dv * c.z / inputs.camera.fy,
                0.0,
            );
            pose = Isometry3::from_parts(
                Translation3::from(predicted.translation.vector + shift),
                predicted.rotation,
            );
        }
        if depth_weight > 0.0 && !fresh {
            self.carried.render(&pose, &roi_camera, &mut self.depth_now);
        }
        let mut depth_stats = None;
        let mut offset = Vector6::zeros();
        let prior_t = 1.0 / (config.prior_translation_m * config.prior_translation_m);
        let prior_r = 1.0 / config.prior_rotation_rad().powi(2);
        for it in 0..config.iterations {
            let mut ne = NormalEquations::default();
            if depth_weight > 0.0 {
                let mut d = NormalEquations::default();
                let s = depth_term.accumulate(
                    &self.view,
                    &pose,
                    &self.center_obj,
                    &roi_camera,
                    &self.depth_now,
                    &mut d,
                );
                depth_stats = Some(s);
                ne.add_scaled(&d, depth_weight);
            }
            if use_event_residuals {
                if it % 2 == 0 {
                    self.edges.associate(
                        &event_term,
                        &self.view,
                        &pose,
                        &self.center_obj,
                        inputs.camera,
                        &self.velocity,
                        window_s,
                    );
                }
                let mut e = NormalEquations::default();
                self.edges.accumulate(
                    &event_term,
                    &self.view,
                    &pose,
                    &self.center_obj,
                    inputs.camera,
                    &mut e,
                );
                ne.add_scaled(&e, config.event_weight);
            }
            if use_intensity {
                if it % 2 == 0 {
                    self.intensity_edges.associate(
                        &intensity_term,
                        &self.view,
                        &pose,
                        inputs.camera,
                        inputs.surface,
                        inputs.t_us,
                        roi.width / f64::from(roi.out_width.max(1)),
                    );
                }
                let mut e = NormalEquations::default();
                self.intensity_edges.accumulate(
                    &intensity_term,
                    &self.view,
                    &pose,
                    &self.center_obj,
                    inputs.camera,
                    &mut e,
                );
                ne.add_scaled(&e, intensity_term.weight);
            }
            // Prior towards the prediction: keeps directions the data cannot see (e.g. rotation about a
            // symmetry axis) where the motion model puts them.
            add_prior(&mut ne, &offset, prior_t, prior_r);
            let Some(step) = solve_step(&ne, config.damping, &bounds) else {
                break;
            };
            offset += step;
            pose = apply_step(&pose, &self.center_obj, &step);
            let (t, r) = (
                step.fixed_rows::<3>(0).norm(),
                step.fixed_rows::<3>(3).norm(),
            );
            if t < 1e-5 && r < 1e-4 {
                break;
            }
        }
        // Safety net at a fresh depth frame: the depth-only refinement from the previous depth frame's pose
        // (what `depth30` would report). If events led the estimate astray, the depth image says so: keep
        // whichever hypothesis more model points agree with.
        if fresh
            && use_events
            && config.depth_fallback_margin >= 0.0
            && let Some((t_anchor, anchor)) = self.anchor
        {
            // Starts: the previous depth frame's pose and, optionally, that pose carried on at the velocity
            // measured between depth frames (neither depends on what the events did since).
            let span = (inputs.t_us - t_anchor).max(0) as f64 * 1e-6;
            let starts = [
                Some(anchor),
                config
                    .depth_fallback_extrapolate
                    .then(|| apply_step(&anchor, &self.center_obj, &(self.velocity * span))),
            ];
            let mut best: Option<(f64, Isometry3<f64>, DepthTermStats)> = None;
            for start in starts.into_iter().flatten() {
                let candidate = self.refine_on_depth(start, &roi_camera, config);
                if best.is_none_or(|(b, _, _)| candidate.0 > b) {
                    best = Some(candidate);
                }
            }
            let (main_fit, main_stats) = self.depth_fit_at(&pose, &roi_camera, config);
            match best {
                Some((fallback_fit, fallback, fallback_stats))
                    if fallback_fit > main_fit + config.depth_fallback_margin =>
                {
                    pose = fallback;
                    depth_stats = Some(fallback_stats);
                    self.fallbacks += 1;
                }
                _ => depth_stats = Some(main_stats),
            }
        }
        if fresh {
            self.depth_frames_used += 1;
            self.carried
                .attach_to_object(&pose, &self.aabb_min, &self.aabb_max, 0.01);
        }
        let support = if use_events && self.image_speed(inputs.camera) > 150.0 {
            self.edges.contour_support(&self.view, &pose, inputs.camera)
        } else {
            None
        };
        let fit = depth_stats.filter(|_| depth_weight >= 1.0);
        self.finish(inputs, pose, fit, support, config);
    }

    /// Fraction of the model's visible points that agree with `self.depth_now` at `pose`, and the term's counts.
    fn depth_fit_at(
        &self,
        pose: &Isometry3<f64>,
        roi_camera: &PinholeCamera,
        config: &TrackerConfig,
    ) -> (f64, DepthTermStats) {
        let mut scratch = NormalEquations::default();
        let s = config.depth_term.accumulate(
            &self.view,
            pose,
            &self.center_obj,
            roi_camera,
            &self.depth_now,
            &mut scratch,
        );
        (s.inliers as f64 / s.points.max(1) as f64, s)
    }

    /// Depth-only refinement from `start` against `self.depth_now` (what `depth30` does at a depth frame): the
    /// refined pose with its agreeing fraction and counts.
    fn refine_on_depth(
        &self,
        start: Isometry3<f64>,
        roi_camera: &PinholeCamera,
        config: &TrackerConfig,
    ) -> (f64, Isometry3<f64>, DepthTermStats) {
        let bounds = StepBounds {
            max_rotation: config.max_step_rotation_deg.to_radians(),
            max_translation: config.max_step_translation_diameters * self.diameter,
        };
        let prior_t = 1.0 / (config.prior_translation_m * config.prior_translation_m);
        let prior_r = 1.0 / config.prior_rotation_rad().powi(2);
        let mut pose = start;
        let mut offset = Vector6::zeros();
        for _ in 0..config.iterations {
            let mut ne = NormalEquations::default();
            config.depth_term.accumulate(
                &self.view,
                &pose,
                &self.center_obj,
                roi_camera,
                &self.depth_now,
                &mut ne,
            );
            add_prior(&mut ne, &offset, prior_t, prior_r);
            let Some(step) = solve_step(&ne, config.damping, &bounds) else {
                break;
            };
            offset += step;
            pose = apply_step(&pose, &self.center_obj, &step);
        }
        let (fit, stats) = self.depth_fit_at(&pose, roi_camera, config);
        (fit, pose, stats)
    }

    /// Checks the hypothesis `self.predicted` against the fresh depth frame of `inputs` (re-detection): registers
    /// the frame around it and refines on depth only from it, using the render the caller made at it in
    /// `self.target`. Returns the agreeing fraction and the refined pose; `None` without a depth frame, ROI or
    /// visible model.
    pub fn probe_depth(
        &mut self,
        inputs: &TickInputs<'_>,
        config: &TrackerConfig,
    ) -> Option<(f64, Isometry3<f64>)> {
        let roi = self.roi?;
        let frame = inputs.depth?;
        let roi_camera = inputs.camera.crop(&roi);
        let start = self.predicted;
        self.view.extract(
            &self.target,
            &roi_camera,
            self.label,
            &start,
            config.max_surface_points,
            config.max_contour_points,
        );
        if self.view.surface.is_empty() {
            return None;
        }
        let c = self.center_at(&start);
        let radius = 0.6 * config.roi_scale * self.diameter + 0.08;
        self.carried
            .register(frame, inputs.depth_rig, &c, radius, inputs.t_us);
        self.carried
            .render(&start, &roi_camera, &mut self.depth_now);
        let (fit, pose, _) = self.refine_on_depth(start, &roi_camera, config);
        Some((fit, pose))
    }

    /// How well the silhouette in `self.target` (rendered at `pose`) matches what the fresh depth image in
    /// `self.depth_now` shows at the object's depth: pixels where model and measurement agree in depth, over
    /// pixels where either the model is or a measurement lies within half a diameter of the centre's depth (an
    /// intersection over union, in [0, 1]). Re-detection ranks places by it: unlike the agreeing fraction of model
    /// points, it stays low for a pose that shows only a small part of the object where the depth sees all of it.
    pub fn silhouette_agreement(&self, pose: &Isometry3<f64>, config: &TrackerConfig) -> f64 {
        let c = self.center_at(pose);
        let band = 0.5 * self.diameter;
        let noise = config.depth_term;
        let tolerance = 3.0 * (noise.sigma_0 + noise.sigma_z2 * c.z * c.z) + 0.005;
        let (mut agree, mut union) = (0usize, 0usize);
        let rendered = self.target.depth().iter().zip(self.target.mask());
        for (&zm, (&zr, &label)) in self.depth_now.z.iter().zip(rendered) {
            let model = label == self.label;
            let measured = zm > 0.0 && (f64::from(zm) - c.z).abs() < band;
            union += usize::from(model || measured);
            agree += usize::from(model && zm > 0.0 && f64::from((zm - zr).abs()) < tolerance);
        }
        agree as f64 / union.max(1) as f64
    }

    /// Moves the object to `pose` found by re-detection: the motion estimate and the depth anchor, which belong
    /// to the place it was lost at, are dropped; the next refinement starts there.
    pub fn relocate(&mut self, pose: Isometry3<f64>) {
        self.pose = normalise(pose);
        self.predicted = self.pose;
        self.velocity = Vector6::zeros();
        self.anchor = None;
        self.low_ticks = 0;
        self.redetections += 1;
    }

    /// Replaces the latest estimate (see [`super::EventTrack6d::reset_pose`]).
    pub fn reset(&mut self, t_us: i64, pose: Isometry3<f64>) {
        self.previous = Some((self.t_us, self.pose));
        self.pose = normalise(pose);
        self.predicted = self.pose;
        self.t_us = t_us;
        self.low_ticks = 0;
        self.state = TrackingState::Tracking;
    }

    /// Holds the latest estimate at `t_us` without refining (`depth30` between depth frames): pose, quality and
    /// state stay what the last refinement said.
    pub fn hold(&mut self, t_us: i64) {
        self.previous = Some((self.t_us, self.pose));
        self.t_us = t_us;
    }

    /// Records the new estimate: quality, state, velocity and the pose history.
    fn finish(
        &mut self,
        inputs: &TickInputs<'_>,
        pose: Isometry3<f64>,
        fresh_depth: Option<DepthTermStats>,
        event_support: Option<f64>,
        config: &TrackerConfig,
    ) {
        // Quality evidence: depth agreement at the last exposure, visibility, event support of the outline.
        let mut visibility = 1.0;
        if let Some(s) = fresh_depth {
            let used = s.measured.max(1) as f64;
            self.depth_fit = s.inliers as f64 / used;
            visibility = (s.measured as f64 / s.points.max(1) as f64).min(1.0);
        }
        let in_view = self.roi.is_some() && self.view.visible_pixels > 0;
        let support = event_support.unwrap_or(1.0);
        let quality = if in_view {
            self.depth_fit * (0.4 + 0.6 * visibility) * (0.6 + 0.4 * support)
        } else {
            0.0
        };
        self.quality = quality.clamp(0.0, 1.0) as f32;
        let q = config.quality;
        if self.quality < q.lost_below {
            self.low_ticks += 1;
        } else {
            self.low_ticks = 0;
        }
        self.state = if self.low_ticks >= q.lost_after_ticks {
            TrackingState::Lost
        } else if self.quality < q.degraded_below {
            TrackingState::Degraded
        } else {
            TrackingState::Tracking
        };

        // Velocity: at a fresh depth frame from the motion since the previous one (anchored on depth, so a drift
        // the motion model itself introduced between frames is not fed back); otherwise from the last tick,
        // weighted less.
        let (reference, span, a) = match (fresh_depth.is_some(), self.anchor) {
            (true, Some((t0, p0))) if inputs.t_us > t0 => (
                p0,
                (inputs.t_us - t0) as f64 * 1e-6,
                config.velocity_smoothing_depth,
            ),
            _ => (self.pose, inputs.dt_s, config.velocity_smoothing),
        };
        if fresh_depth.is_some() {
            self.anchor = Some((inputs.t_us, pose));
        }
        if span > 0.0 && self.state != TrackingState::Lost {
            let c0 = self.center_at(&reference);
            let c1 = self.center_at(&pose);
            let dv = (c1 - c0) / span;
            let dw = (pose.rotation * reference.rotation.inverse()).scaled_axis() / span;
            let measured = Vector6::new(dv.x, dv.y, dv.z, dw.x, dw.y, dw.z);
            let a = a.clamp(0.0, 1.0);
            let mut v = a * measured + (1.0 - a) * self.velocity;
            let lin = v.fixed_rows::<3>(0).norm();
            if lin > config.max_speed {
                v.fixed_rows_mut::<3>(0).scale_mut(config.max_speed / lin);
            }
            let ang = v.fixed_rows::<3>(3).norm();
            if ang > config.max_angular_speed {
                v.fixed_rows_mut::<3>(3)
                    .scale_mut(config.max_angular_speed / ang);
            }
            self.velocity = v;
        } else if self.state == TrackingState::Lost {
            self.velocity = Vector6::zeros();
        }
        self.previous = Some((self.t_us, self.pose));
        self.pose = normalise(pose);
        self.t_us = inputs.t_us;
    }
}

/// Adds the prior towards the refinement's start: `offset` is the increment accumulated so far, `prior_t` and
/// `prior_r` the inverse variances of translation (1/m^2) and rotation (1/rad^2).
fn add_prior(ne: &mut NormalEquations, offset: &Vector6<f64>, prior_t: f64, prior_r: f64) {
    for k in 0..6 {
        let w = if k < 3 { prior_t } else { prior_r };
        ne.h[(k, k)] += w;
        ne.g[k] += w * offset[k];
    }
}

/// Re-normalises the rotation (drift from repeated composition).
fn normalise(pose: Isometry3<f64>) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::from(pose.translation.vector),
        UnitQuaternion::new_normalize(*pose.rotation.quaternion()),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn contains(roi: &Roi, camera: &PinholeCamera, p: &Point3<f64>, margin_px: f64) -> bool {
        let uv = camera.project(p).expect("in front");
        uv.x >= roi.x + margin_px
            && uv.y >= roi.y + margin_px
            && uv.x <= roi.x + roi.width - margin_px
            && uv.y <= roi.y + roi.height - margin_px
    }

    #[test]
    fn roi_at_a_depth_exposure_widens_to_the_extrapolated_start_only_when_asked() {
        let camera = PinholeCamera::new(600.0, 600.0, 639.5, 359.5, 1280, 720).unwrap();
        let mut config = TrackerConfig::default();
        let at = |x: f64| Isometry3::translation(x, 0.0, 0.6);
        let half = Vector3::new(0.05, 0.05, 0.05);
        let mut track = ObjectTrack::new(1, 0.1, -half, half, at(0.0), 0, &config);
        // The previous depth pose 33 ms ago at x = 0, moving at 3 m/s along x: the extrapolated start is
        // 10 cm (one diameter) away from a prediction that stayed at x = 0.
        track.anchor = Some((0, at(0.0)));
        track.velocity = Vector6::new(3.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        track.predicted = at(0.0);
        let t = 33_333;
        let extrapolated = Point3::new(0.1, 0.0, 0.6);
        let plain = track.update_roi(&camera, &config, t, true).unwrap();
        assert!(!contains(&plain, &camera, &extrapolated, 0.0));
        config.roi_widen_at_depth = true;
        let between = track.update_roi(&camera, &config, t, false).unwrap();
        assert_eq!(between, plain, "only depth exposures widen");
        let wide = track.update_roi(&camera, &config, t, true).unwrap();
        // Half a diameter (50 px at 0.6 m) of the object on either side fits in the ROI.
        for p in [Point3::new(0.0, 0.0, 0.6), extrapolated] {
            assert!(contains(&wide, &camera, &p, 40.0), "{wide:?} misses {p:?}");
        }
    }
}

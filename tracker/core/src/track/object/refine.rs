//! The per-tick refinement of one object: events, carried depth and intensity in a few Gauss-Newton steps,
//! with the depth-only safety net at fresh depth frames.

use super::depth_check::{seen_agreement, weaker_fit};
use super::{ObjectTrack, TickInputs, add_prior};
use crate::refine::{
    BinnedWindow, EventTermKind, NormalEquations, StepBounds, apply_step, solve_step,
};
use crate::track::config::{DepthUse, TrackerConfig};
use crate::track::estimate::TrackingState;
use crate::track::fallback_check::{DepthFallbackCheck, FALLBACK_STARTS, FallbackCandidate};
use nalgebra::{Isometry3, Translation3, Vector3, Vector6};
use scene::geometry::PinholeCamera;

/// The depth a tick's refinement uses, prepared by [`ObjectTrack::prepare_depth`] before the ROI render is taken.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct TickDepth {
    /// A depth frame was registered as the new `D_0` at this tick (exposed now, or late and carried here).
    fresh: bool,
    /// Weight of the depth term (1 for a fresh frame, `carried_depth_weight` between frames, 0 without depth).
    weight: f64,
    /// `depth_now` holds `D_t` rendered at the predicted pose.
    at_predicted: bool,
}

impl ObjectTrack {
    /// Registers this tick's depth frame as the new `D_0` and renders `D_t` at the predicted pose in the ROI chosen
    /// by [`Self::update_roi`]. None of it reads the ROI render, so the tracker runs it before taking the render:
    /// a render that is still in flight (prefetched on a GPU) overlaps this work.
    pub fn prepare_depth(&mut self, inputs: &TickInputs<'_>, config: &TrackerConfig) -> TickDepth {
        self.late_motion = None;
        self.late_frame = None;
        let Some(roi) = self.roi else {
            return TickDepth::default();
        };
        let roi_camera = inputs.camera.crop(&roi);
        let predicted = self.predicted;
        let mut fresh = inputs.depth.is_some()
            && match config.depth {
                DepthUse::EveryTick | DepthUse::DepthFramesOnly => true,
                DepthUse::FirstFrameOnly => self.depth_frames_used == 0,
                DepthUse::Off => false,
            };
        // A frame exposed at an earlier tick is placed by the estimate then; without one it is of no use.
        let mut late_from = None;
        if fresh && inputs.depth_exposed_us < inputs.t_us {
            late_from = self.history.at(inputs.depth_exposed_us);
            if late_from.is_none() {
                self.late_depth_unplaced += 1;
                fresh = false;
            }
        }
        let mut depth = TickDepth::default();
        if fresh {
            if let Some(frame) = inputs.depth {
                self.capture_neighbourhood(frame, inputs.depth_rig, config);
                match late_from {
                    // Aligned and carried by the refinement, which needs the model view of the ROI render.
                    Some(then) => self.register_late_depth(
                        frame,
                        inputs.depth_rig,
                        inputs.depth_exposed_us,
                        &then,
                        config,
                    ),
                    None => {
                        self.carry_depth_from(frame, inputs.depth_rig, inputs.t_us, config);
                        self.carried
                            .render(&predicted, &roi_camera, &mut self.depth_now);
                    }
                }
                depth = TickDepth {
                    fresh: true,
                    weight: 1.0,
                    at_predicted: true,
                };
            }
        } else if config.depth == DepthUse::EveryTick && !self.carried.is_empty() {
            // Rendered at the pose the refinement starts from: here if the occluded outline is hidden, which needs
            // it at the prediction, else in `refine`.
            depth.weight = config.carried_depth_weight;
            if config.hide_occluded_outline && depth.weight > 0.0 {
                self.carried
                    .render(&predicted, &roi_camera, &mut self.depth_now);
                depth.at_predicted = true;
            }
        }
        depth
    }

    /// The event window this tick's refinement reads, microseconds: about `event_window_px` of the outline's
    /// predicted image motion, within the configured bounds.
    fn event_window_us(&self, camera: &PinholeCamera, config: &TrackerConfig) -> i64 {
        let speed = self.image_speed(camera).max(1.0);
        let window = ((config.event_window_px / speed) * 1e6) as i64;
        window.clamp(config.min_event_window_us, config.max_event_window_us)
    }

    /// Bins the events of this tick's window in the ROI chosen by [`Self::update_roi`], which needs no render:
    /// the tracker runs it before taking the render, so that a render still in flight overlaps it. The
    /// refinement reuses the bins.
    pub fn prepare_events(&mut self, inputs: &TickInputs<'_>, config: &TrackerConfig) {
        if !config.events {
            return;
        }
        if let Some(roi) = self.roi {
            let window = BinnedWindow {
                t_us: inputs.t_us,
                window_us: self.event_window_us(inputs.camera, config),
                roi,
            };
            self.edges.bin_ahead(inputs.surface, window);
        }
    }

    /// Refines the predicted pose at this tick from the render already in `self.target` (made at the predicted
    /// poses of all objects) and `depth` from [`Self::prepare_depth`], and updates quality, state and velocity.
    pub fn refine(&mut self, inputs: &TickInputs<'_>, config: &TrackerConfig, depth: TickDepth) {
        self.fallback_check = None;
        // Events binned ahead of the render at this tick ([`Self::prepare_events`]), if any.
        let prebinned = self.edges.take_prebinned();
        let Some(roi) = self.roi else {
            if depth.fresh {
                // The render failed after the frame was registered: its points move with the pose reported (a
                // late frame's are split where the object was estimated at the exposure).
                let split_at = match self.late_frame.take() {
                    Some((_, then)) => then,
                    None => self.predicted,
                };
                self.carried
                    .attach_to_object(&split_at, &self.aabb_min, &self.aabb_max, 0.01);
            }
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
        let TickDepth {
            fresh,
            weight: depth_weight,
            at_predicted: depth_now_at_predicted,
        } = depth;
        // A late frame: checked at its exposure, and the refinement starts from the prediction corrected there.
        let late = fresh && self.late_frame.is_some();
        let (predicted, late_fit) = if late {
            let use_events = config.events && !self.view.contour.is_empty();
            self.carry_late_depth(inputs, &roi_camera, use_events, config)
        } else {
            (predicted, None)
        };
        // Outline the depth shows behind a nearer surface (a hand gripping the object) fires no events: leave it
        // out of the event and intensity terms rather than pull it onto the occluder's edges.
        if config.hide_occluded_outline && depth_weight > 0.0 {
            self.view.hide_occluded_contour(
                &self.depth_now,
                &roi_camera,
                &predicted,
                config.depth_term.occlusion_gap,
                config.hide_occluded_max_share,
            );
        }
        // Until its first depth frame, for as long as a late one could still come, an object holds its first
        // pose: events alone, with no depth to anchor them, drift (a live depth camera's first frame arrives tens
        // of milliseconds after the first tick).
        let awaiting_depth = self.depth_frames_used == 0
            && (inputs.t_us - self.first_us) as f64 <= config.max_depth_age_ms * 1e3;
        let refine_now = match config.depth {
            DepthUse::DepthFramesOnly => fresh,
            DepthUse::Off => true,
            DepthUse::EveryTick | DepthUse::FirstFrameOnly => fresh || !awaiting_depth,
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
            let window = self.event_window_us(inputs.camera, config);
            window_s = window as f64 * 1e-6;
            // Another object nearer than this one's centre hides it: its events are its own.
            let occluder_z = self.center_at(&predicted).z as f32;
            self.edges.collect(
                &event_term,
                inputs.surface,
                &roi,
                self.target.mask(),
                self.target.depth(),
                occluder_z,
                self.label,
                inputs.t_us,
                window,
                config.max_event_points,
                prebinned,
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
                (event_term.search_aperture_tolerance > 0.0)
                    .then(|| self.image_motion_direction(&predicted, inputs))
                    .flatten(),
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
        if depth_weight > 0.0 && !fresh && !(depth_now_at_predicted && pose == predicted) {
            self.carried.render(&pose, &roi_camera, &mut self.depth_now);
        }
        let mut depth_stats = None;
        // The final pose's event support, when the safety net already measured it.
        let mut measured_support = None;
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
        // whichever hypothesis more of the model points in view agree with, unless the surroundings contradict its
        // motion ([`DepthFallbackCheck::replacement`]). A late frame had its check at its exposure.
        if fresh
            && !late
            && use_events
            && config.depth_fallback_margin >= 0.0
            && let Some((t_anchor, anchor)) = self.anchor
        {
            let starts = self.fallback_starts(t_anchor, &anchor, inputs.t_us, config);
            let main_stats = self.depth_stats_at(&pose, &roi_camera, config);
            let mut check = DepthFallbackCheck {
                object: usize::from(self.label) - 1,
                t_us: inputs.t_us,
                tick_us: inputs.t_us,
                estimate: pose,
                estimate_agreeing: seen_agreement(&main_stats),
                estimate_motion_agreeing: self.motion_agreement_at(&pose, inputs, config),
                estimate_event_support: self.edges.contour_support(
                    &self.view,
                    &pose,
                    inputs.camera,
                ),
                candidates: [None; FALLBACK_STARTS],
                replaced_by: None,
            };
            let mut candidate_stats = [None; FALLBACK_STARTS];
            for (k, start) in starts.into_iter().enumerate() {
                let Some((kind, from)) = start else { continue };
                let (refined, stats) = self.refine_on_depth(from, &roi_camera, config);
                check.candidates[k] = Some(FallbackCandidate {
                    start: kind,
                    pose: refined,
                    agreeing: seen_agreement(&stats),
                    motion_agreeing: self.motion_agreement_at(&refined, inputs, config),
                    event_support: self
                        .edges
                        .contour_support(&self.view, &refined, inputs.camera),
                });
                candidate_stats[k] = Some(stats);
            }
            check.replaced_by = check.replacement(&config.fallback_rule());
            let replacement = check
                .replaced_by
                .and_then(|k| Some((check.candidates[k]?, candidate_stats[k]?)));
            match replacement {
                Some((candidate, stats)) => {
                    pose = candidate.pose;
                    depth_stats = Some(stats);
                    measured_support = Some(candidate.event_support);
                    self.fallbacks += 1;
                }
                None => {
                    depth_stats = Some(main_stats);
                    measured_support = Some(check.estimate_event_support);
                }
            }
            self.fallback_check = Some(check);
        }
        if fresh {
            self.depth_frames_used += 1;
            self.carried
                .attach_to_object(&pose, &self.aabb_min, &self.aabb_max, 0.01);
        }
        let support = if use_events && self.image_speed(inputs.camera) > 150.0 {
            measured_support
                .unwrap_or_else(|| self.edges.contour_support(&self.view, &pose, inputs.camera))
        } else {
            None
        };
        // A late frame's evidence is the weaker of its agreement at the exposure, with the pose checked there,
        // and at the tick, where its object part agrees with the events' motion by construction but its
        // background and hand stay where they were measured.
        let fit = if late {
            weaker_fit(late_fit, depth_stats)
        } else {
            depth_stats.filter(|_| depth_weight >= 1.0)
        };
        self.finish(inputs, pose, fit, support, config);
    }
}

impl ObjectTrack {
    /// Unit image direction (full-image pixels) the centre at `predicted` moves in at the estimated velocity,
    /// when it moves at least 2 px per tick and at least as far as turning moves the outline's ends;
    /// `None` otherwise, and before the third depth frame (the motion is not measured yet).
    fn image_motion_direction(
        &self,
        predicted: &Isometry3<f64>,
        inputs: &TickInputs<'_>,
    ) -> Option<[f64; 2]> {
        if self.depth_frames_used < 2 {
            return None;
        }
        let c = self.center_at(predicted);
        let v = Vector3::new(self.velocity[0], self.velocity[1], self.velocity[2]);
        let a = inputs.camera.project(&c)?;
        let b = inputs.camera.project(&(c + v * inputs.dt_s))?;
        let d = [b.x - a.x, b.y - a.y];
        let n = d[0].hypot(d[1]);
        // Turning moves the outline's ends in other directions than the centre: only a mostly sliding outline
        // has one direction of motion.
        let w = Vector3::new(self.velocity[3], self.velocity[4], self.velocity[5]).norm();
        let turning = inputs.camera.fx * w * self.diameter * 0.5 / c.z.max(0.05) * inputs.dt_s;
        (n >= 2.0 && n >= turning).then(|| [d[0] / n, d[1] / n])
    }
}

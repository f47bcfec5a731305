//! The search for objects the tracker fell off, at a depth frame: object-sized foreground clusters of the
//! depth image, each tried with a depth-only refinement (see [`crate::track::redetect`]).

use super::EventTrack6d;
use crate::render::{RenderTarget, Scene, SceneObject};
use crate::track::TrackingState;
use crate::track::object::TickInputs;
use crate::track::redetect::cluster_centres;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

impl EventTrack6d {
    /// At a depth frame: every object that is not `tracking` is checked, on depth alone, where it is predicted
    /// and at the object-sized clusters of foreground (with the predicted orientation and with its longest axis
    /// along the cluster's); it moves to the best place if that scores clearly better than the prediction.
    pub(super) fn redetect(&mut self, t_us: i64, dt_s: f64) {
        let cfg = self.config.redetect;
        let r = &mut self.redetection;
        let mut foreground_ready = false;
        for k in 0..self.objects.len() {
            let o = &self.objects[k];
            if o.state == TrackingState::Tracking || t_us < o.t_us {
                continue;
            }
            if !foreground_ready {
                r.foreground.clear();
                let noise = self.config.depth_term;
                let margin = |z: f64| {
                    let sigma = noise.sigma_0 + noise.sigma_z2 * z * z;
                    cfg.foreground_margin_m.max(cfg.foreground_sigmas * sigma)
                };
                r.background
                    .foreground(&self.depth, &self.rig.depth, margin, &mut r.foreground);
                foreground_ready = true;
            }
            r.centres.clear();
            cluster_centres(
                &r.foreground,
                0.5 * o.diameter,
                // The visible surface lies in front of the centre by about half the thinnest extent.
                0.5 * (o.aabb_max - o.aabb_min).min(),
                cfg.candidates,
                &mut r.seeds,
                &mut r.centres,
            );
            if r.centres.is_empty() {
                continue;
            }
            let predicted = o.predicted;
            let predicted_centre = o.center_at(&predicted);
            let diameter = o.diameter;
            let center_obj = o.center_obj;
            let max_surface = self.config.max_surface_points;
            // Samples the object's two largest box extents cover at 1 m.
            let size = o.aabb_max - o.aabb_min;
            // The object's longest box axis, object frame.
            let long_axis = Vector3::ith_axis(size.imax()).into_inner();
            let mut extent = size.data.0[0];
            extent.sort_by(|a, b| b.total_cmp(a));
            let min_support = cfg.min_support
                * extent[0]
                * extent[1]
                * r.background.samples_per_m2_at_1m(&self.rig.depth);
            let mut probe = |start: Isometry3<f64>| {
                let o = &mut self.objects[k];
                o.predicted = start;
                self.scene[k].pose = start;
                let roi = o.update_roi(&self.rig.event_camera, &self.config, t_us, false)?;
                let camera = &self.rig.event_camera;
                let mut render = |scene: &[SceneObject], target: &mut RenderTarget| {
                    let scene = Scene::objects(scene)
                        .geometry_only()
                        .normals_on_surface_grid(max_surface);
                    let ok = self
                        .renderer
                        .render_roi(&scene, camera, &roi, target)
                        .is_ok();
                    self.counters.render_errors += u64::from(!ok);
                    ok
                };
                if !render(&self.scene, &mut o.target) {
                    return None;
                }
                let inputs = TickInputs {
                    t_us,
                    dt_s,
                    depth: Some(&self.depth),
                    surface: &self.surface,
                    camera: &self.rig.event_camera,
                    depth_rig: &self.rig.depth,
                };
                let (fit, pose) = o.probe_depth(&inputs, &self.config)?;
                // Ranked by the silhouette at the refined pose, in the same ROI.
                self.scene[k].pose = pose;
                if !render(&self.scene, &mut o.target) {
                    return None;
                }
                // Both directions: model points the depth confirms, and depth at the object's range the model
                // explains (a pose showing a small part of the object can fit that part perfectly).
                Some((
                    fit * o.silhouette_agreement(&pose, &self.config).sqrt(),
                    pose,
                ))
            };
            let here = probe(predicted).map_or(0.0, |(fit, _)| fit);
            let mut best: Option<(f64, Isometry3<f64>)> = None;
            for cluster in &r.centres {
                let centre = cluster.centre;
                if (centre - predicted_centre).norm() < 0.25 * diameter
                    || (cluster.support as f64)
                        < (min_support / (centre.z * centre.z).max(1e-6)).max(8.0)
                {
                    continue;
                }
                // Orientations: the predicted one, and the predicted one turned the least that lays the
                // object's longest axis along the cluster's principal axis.
                let current = predicted.rotation * long_axis;
                let target = if current.dot(&cluster.axis) >= 0.0 {
                    cluster.axis
                } else {
                    -cluster.axis
                };
                let aligned = UnitQuaternion::rotation_between(&current, &target)
                    .map(|q| q * predicted.rotation)
                    .filter(|_| current.angle(&target) > 15f64.to_radians());
                for rotation in [Some(predicted.rotation), aligned].into_iter().flatten() {
                    let start = Isometry3::from_parts(
                        Translation3::from(centre.coords - rotation * center_obj),
                        rotation,
                    );
                    if let Some((fit, pose)) = probe(start)
                        && best.is_none_or(|(b, _)| fit > b)
                    {
                        best = Some((fit, pose));
                    }
                }
            }
            let o = &mut self.objects[k];
            o.predicted = predicted;
            if let Some((fit, pose)) = best
                && fit >= cfg.min_score
                && fit > here + cfg.margin
            {
                o.relocate(pose);
            }
            self.scene[k].pose = o.predicted;
        }
    }
}

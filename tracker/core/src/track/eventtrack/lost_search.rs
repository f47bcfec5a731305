//! The search for objects the tracker fell off: planned at a depth frame from the object-sized foreground
//! clusters of the depth image (see [`crate::track::redetect`]), then carried out a few places per tick, each
//! place tried with a depth-only refinement against that frame.

use super::counters::TrackerCounters;
use super::place_check::{PendingPlace, PlaceCheck, PlaceResult, ProbeSet};
use super::pose_places::PoseSearch;
use super::renderers::Renderers;
use super::setup::TrackingRig;
use crate::recon::EventSurface;
use crate::track::TrackingState;
use crate::track::config::{DepthUse, TrackerConfig};
use crate::track::object::{ObjectTrack, TickInputs};
use crate::track::pose_search::{HypothesisScoring, ShapeSamples};
use crate::track::redetect::{Cluster, DepthBackground, RedetectConfig, cluster_centres};
use drivers::recording::DepthFrame;
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use scene::geometry::PinholeCamera;
use scene::render::SceneObject;
use std::collections::VecDeque;

/// One object's search in progress.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Search {
    /// Score at the prediction.
    here: f64,
    /// Best other place so far: score and refined pose.
    best: Option<(f64, Isometry3<f64>)>,
    /// Places still pending.
    remaining: usize,
}

/// Re-detection state shared by all objects: the learned background and reused buffers.
pub(super) struct Redetection {
    pub(super) background: DepthBackground,
    /// The depth frame the tracker holds was used at a tick but is not folded into `background` yet: folding it
    /// waits until the background is read, the tick's poses are out, or the frame is replaced, whichever is first.
    pub(super) background_behind: bool,
    pub(super) foreground: Vec<Point3<f64>>,
    pub(super) seeds: Vec<(usize, Point3<f64>)>,
    pub(super) centres: Vec<Cluster>,
    /// Places still to check, in order, against the depth frame `frame` (index, exposure time in microseconds).
    pub(super) pending: VecDeque<PendingPlace>,
    pub(super) frame: Option<(u64, i64)>,
    /// Every object where it was estimated at `frame`'s exposure (predicted, for a frame on time): the places
    /// are checked with the others there.
    pub(super) scene: Vec<SceneObject>,
    /// Per object: the search's results so far.
    pub(super) searches: Vec<Search>,
    /// The places being checked at this tick and their results.
    pub(super) checks: Vec<PendingPlace>,
    pub(super) results: Vec<PlaceResult>,
    /// Scratch tracks for the checks, one set per renderer (thread).
    pub(super) probes: Vec<ProbeSet>,
    /// The whole-pose search's shapes, orientations and scratch.
    pub(super) pose_search: PoseSearch,
    /// The whole-pose search's best poses for the object being planned.
    pub(super) poses: Vec<Isometry3<f64>>,
    /// The tick of the latest plan (microseconds), and the ticks between the two latest plans (0 until measured):
    /// how many ticks a search has to check its places in.
    planned_us: Option<i64>,
    ticks_per_frame: usize,
}

/// The depth frame a search's places are checked against, and what the checks read beside it.
pub(super) struct SearchFrame<'a> {
    pub config: &'a TrackerConfig,
    pub rig: &'a TrackingRig,
    /// The depth frame the places were planned on (the tracker's latest).
    pub depth: &'a DepthFrame,
    pub surface: &'a EventSurface,
}

impl Search {
    /// Records the result of checking `place`; once the search is complete, returns the place to move the object
    /// to, with its score, if the best one scores at least `min_score` and beats the estimate's place by more
    /// than `margin`.
    fn record(
        &mut self,
        place: &PendingPlace,
        result: PlaceResult,
        cfg: &RedetectConfig,
    ) -> Option<(f64, Isometry3<f64>)> {
        self.remaining -= 1;
        if place.estimated {
            self.here = result.map_or(0.0, |(score, _)| score);
        } else if let Some((score, pose)) = result
            && self.best.is_none_or(|(b, _)| score > b)
        {
            self.best = Some((score, pose));
        }
        let (score, pose) = self.best.filter(|_| self.remaining == 0)?;
        (score >= cfg.min_score && score > self.here + cfg.margin).then_some((score, pose))
    }
}

impl Redetection {
    /// Empty re-detection state for the objects of `scene` seen by the depth camera `depth_cam`, with `probes`
    /// (one set per renderer) to check places in.
    pub(super) fn new(
        config: &TrackerConfig,
        scene: &[SceneObject],
        depth_cam: &PinholeCamera,
        probes: Vec<ProbeSet>,
        shapes: Vec<ShapeSamples>,
    ) -> Self {
        let objects = scene.len();
        let places =
            objects * (1 + 2 * config.redetect.candidates + config.redetect.pose_search_places);
        let cell = config.redetect.cell_px.max(1);
        Self {
            background: DepthBackground::new(cell, depth_cam.width, depth_cam.height),
            background_behind: false,
            foreground: Vec::with_capacity(
                (depth_cam.width / cell) as usize * (depth_cam.height / cell) as usize,
            ),
            seeds: Vec::with_capacity(128),
            centres: Vec::with_capacity(config.redetect.candidates),
            pending: VecDeque::with_capacity(places),
            frame: None,
            scene: scene.to_vec(),
            searches: vec![Search::default(); objects],
            checks: Vec::with_capacity(places),
            results: Vec::with_capacity(places),
            probes,
            pose_search: PoseSearch::new(&config.redetect, shapes),
            poses: Vec::with_capacity(config.redetect.pose_search_places),
            planned_us: None,
            ticks_per_frame: 0,
        }
    }

    /// Folds `frame`, the depth frame of the latest depth tick, into the background if it is not yet.
    pub(super) fn catch_up(&mut self, frame: &DepthFrame) {
        if self.background_behind {
            self.background.update(frame);
            self.background_behind = false;
        }
    }

    /// At a depth frame exposed at `exposed_us` and used at the tick `t_us` (`dt_s` after the one before): plans
    /// the search for every object that needs one (not `tracking`, and not merely partly hidden; see
    /// [`crate::track::object::ObjectState::needs_search`]): where it was estimated at the exposure (predicted,
    /// for a frame on time), then the object-sized clusters of foreground (with that orientation and with its
    /// longest axis along the cluster's). A late frame shows where the object was at its exposure, so it is
    /// searched for there; an object whose estimates do not reach back to the exposure is not searched for on
    /// that frame. Places left over from the previous frame are dropped and counted, and so are an object's places
    /// beyond [`Self::places_per_object`].
    #[allow(clippy::too_many_arguments)]
    pub(super) fn plan(
        &mut self,
        config: &TrackerConfig,
        counters: &mut TrackerCounters,
        depth: &DepthFrame,
        rig: &TrackingRig,
        objects: &[ObjectTrack],
        t_us: i64,
        exposed_us: i64,
        dt_s: f64,
    ) {
        let cfg = config.redetect;
        let r = self;
        counters.redetect_places_dropped += r.pending.len() as u64;
        r.pending.clear();
        r.frame = Some((depth.index, exposed_us));
        if let Some(previous) = r.planned_us
            && t_us > previous
            && dt_s > 0.0
        {
            let ticks = ((t_us - previous) as f64 * 1e-6 / dt_s).round();
            if (1.0..=64.0).contains(&ticks) {
                r.ticks_per_frame = ticks as usize;
            }
        }
        r.planned_us = Some(t_us);
        let searching = objects
            .iter()
            .filter(|o| o.state.needs_search(&config.quality) && t_us >= o.state.t_us)
            .count();
        let cap = r.places_per_object(config, searching);
        let at_frame = |o: &ObjectTrack| {
            if exposed_us < t_us {
                o.state.history.at(exposed_us)
            } else {
                Some(o.state.predicted)
            }
        };
        for (s, o) in r.scene.iter_mut().zip(objects) {
            s.pose = at_frame(o).unwrap_or(o.state.predicted);
        }
        let mut foreground_ready = false;
        for (k, o) in objects.iter().enumerate() {
            r.searches[k] = Search::default();
            if !o.state.needs_search(&config.quality) || t_us < o.state.t_us {
                continue;
            }
            let Some(here) = at_frame(o) else {
                continue;
            };
            if !foreground_ready {
                r.find_foreground(config, depth, rig);
                r.pose_search.foreground_found(&r.background);
                foreground_ready = true;
            }
            r.centres.clear();
            cluster_centres(
                &r.foreground,
                0.5 * o.model.diameter,
                // The visible surface lies in front of the centre by about half the thinnest extent.
                0.5 * (o.model.aabb_max - o.model.aabb_min).min(),
                cfg.candidates,
                &mut r.seeds,
                &mut r.centres,
            );
            if !r.centres.is_empty() || r.pose_search.enabled() {
                r.queue_places(k, o, &here, config, depth, rig);
                let queued = r.searches[k].remaining;
                if queued > cap {
                    // The least likely places (the clusters' last orientations) are the ones left out.
                    r.pending.truncate(r.pending.len() - (queued - cap));
                    r.searches[k].remaining = cap;
                    counters.redetect_places_dropped += (queued - cap) as u64;
                }
            }
        }
    }

    /// How many places each of `searching` objects may queue at a depth frame: as many as the ticks until the
    /// next frame check (`places_per_tick` per tick, over all objects), so that every search completes; no limit
    /// when all of a frame's places are checked at once, or before the ticks between two frames are known.
    fn places_per_object(&self, config: &TrackerConfig, searching: usize) -> usize {
        let per_tick = config.redetect.places_per_tick;
        if per_tick == 0
            || config.modalities.depth == DepthUse::DepthFramesOnly
            || self.ticks_per_frame == 0
        {
            return usize::MAX;
        }
        // Each object keeps at least its estimate's place and one other.
        (per_tick * self.ticks_per_frame / searching.max(1)).max(2)
    }

    /// The foreground of the latest depth frame against the learned background (the background caught up
    /// first), into `self.foreground`.
    fn find_foreground(&mut self, config: &TrackerConfig, depth: &DepthFrame, rig: &TrackingRig) {
        let cfg = config.redetect;
        self.catch_up(depth);
        self.foreground.clear();
        let noise = config.depth_term;
        let margin = |z: f64| {
            let sigma = noise.sigma_0 + noise.sigma_z2 * z * z;
            cfg.foreground_margin_m.max(cfg.foreground_sigmas * sigma)
        };
        self.background
            .foreground(depth, &rig.depth, margin, &mut self.foreground);
    }

    /// Queues the places of object `k` (track `o`, estimated at `here` at the frame's exposure): `here` first,
    /// then each foreground cluster in `self.centres` away from it and large enough for the object, with the
    /// estimated orientation and with the object's longest axis laid along the cluster's.
    fn queue_places(
        &mut self,
        k: usize,
        o: &ObjectTrack,
        here: &Isometry3<f64>,
        config: &TrackerConfig,
        depth: &DepthFrame,
        rig: &TrackingRig,
    ) {
        let cfg = config.redetect;
        let here_centre = o.model.center_at(here);
        // Samples the object's two largest box extents cover at 1 m.
        let size = o.model.aabb_max - o.model.aabb_min;
        // The object's longest box axis, object frame.
        let long_axis = Vector3::ith_axis(size.imax()).into_inner();
        let mut extent = size.data.0[0];
        extent.sort_by(|a, b| b.total_cmp(a));
        let min_support = cfg.min_support
            * extent[0]
            * extent[1]
            * self.background.samples_per_m2_at_1m(&rig.depth);
        let before = self.pending.len();
        self.pending.push_back(PendingPlace {
            object: k,
            start: *here,
            estimated: true,
        });
        if self.pose_search.enabled() {
            let z = o.model.center_at(here).z;
            let noise = &config.depth_term;
            let scoring = HypothesisScoring {
                agree_m: 0.01 + 2.0 * (noise.sigma_0 + noise.sigma_z2 * z * z),
                occluder_m: noise.occlusion_gap,
                align_m: 0.25 * o.model.diameter,
            };
            self.poses.clear();
            self.pose_search.best_places(
                k,
                &o.model,
                here,
                &self.centres,
                depth,
                &rig.depth,
                &self.background,
                &scoring,
                &mut self.poses,
            );
            for start in &self.poses {
                self.pending.push_back(PendingPlace {
                    object: k,
                    start: *start,
                    estimated: false,
                });
            }
        }
        for cluster in &self.centres {
            let centre = cluster.centre;
            if (centre - here_centre).norm() < 0.25 * o.model.diameter
                || (cluster.support as f64)
                    < (min_support / (centre.z * centre.z).max(1e-6)).max(8.0)
            {
                continue;
            }
            // Orientations: the estimated one, and the estimated one turned the least that lays the object's
            // longest axis along the cluster's principal axis.
            let current = here.rotation * long_axis;
            let target = if current.dot(&cluster.axis) >= 0.0 {
                cluster.axis
            } else {
                -cluster.axis
            };
            let aligned = UnitQuaternion::rotation_between(&current, &target)
                .map(|q| q * here.rotation)
                .filter(|_| current.angle(&target) > 15f64.to_radians());
            for rotation in [Some(here.rotation), aligned].into_iter().flatten() {
                self.pending.push_back(PendingPlace {
                    object: k,
                    start: Isometry3::from_parts(
                        Translation3::from(centre.coords - rotation * o.model.center_obj),
                        rotation,
                    ),
                    estimated: false,
                });
            }
        }
        self.searches[k].remaining = self.pending.len() - before;
    }

    /// Checks up to `places_per_tick` pending places (all of them when it is 0, or for a tracker that refines only
    /// at depth frames) against the depth frame they were planned on, split over the tracker's threads; an object
    /// whose search is complete moves to its best place if that scores clearly better than its estimate did. A
    /// search is abandoned when the object is `tracking` again. Every check sees the other objects where they were
    /// at the frame's exposure; the moves are made after all of them. A place found on a late frame is where the
    /// object was at its exposure ([`ObjectTrack::relocate_on`] says how it is carried on).
    pub(super) fn continue_search(
        &mut self,
        frame: &SearchFrame<'_>,
        counters: &mut TrackerCounters,
        objects: &mut [ObjectTrack],
        scene: &mut [SceneObject],
        renderers: &mut Renderers,
        dt_s: f64,
    ) {
        let config = frame.config;
        let cfg = config.redetect;
        // A tracker that refines only at depth frames (`depth30`) has no ticks in between to spread over.
        let budget =
            if cfg.places_per_tick == 0 || config.modalities.depth == DepthUse::DepthFramesOnly {
                usize::MAX
            } else {
                cfg.places_per_tick
            };
        let Some((frame_index, frame_t_us)) = self.frame else {
            return;
        };
        let r = self;
        if frame_index != frame.depth.index {
            counters.redetect_places_dropped += r.pending.len() as u64;
            r.pending.clear();
            return;
        }
        r.checks.clear();
        while r.checks.len() < budget {
            let Some(place) = r.pending.pop_front() else {
                break;
            };
            if objects[place.object].state.tracking == TrackingState::Tracking {
                r.searches[place.object].remaining -= 1;
                continue;
            }
            r.checks.push(place);
        }
        if r.checks.is_empty() {
            return;
        }
        counters.redetect_places_checked += r.checks.len() as u64;
        r.results.clear();
        r.results.resize(r.checks.len(), None);
        let check = PlaceCheck {
            objects,
            scene: &r.scene,
            camera: &frame.rig.event_camera,
            config,
            inputs: TickInputs {
                span: 1.0,
                t_us: frame_t_us,
                dt_s,
                inner: false,
                velocity_since_us: None,
                depth: Some(frame.depth),
                depth_exposed_us: frame_t_us,
                surface: frame.surface,
                camera: &frame.rig.event_camera,
                depth_rig: &frame.rig.depth,
            },
        };
        counters.render_errors +=
            check.run_split(&r.checks, &mut r.results, &mut r.probes, renderers);
        for (place, result) in r.checks.iter().zip(&r.results) {
            let k = place.object;
            if let Some((score, found)) = r.searches[k].record(place, *result, &cfg) {
                let o = &mut objects[k];
                o.relocate_on(frame.depth, &frame.rig.depth, found, frame_t_us, config);
                // The depth agreement the quality holds until the next frame is the new place's, not the one it
                // left (its run of poor ticks goes on, so a place that does not hold still ends `lost`).
                o.state.depth_fit = score.clamp(0.0, 1.0);
                scene[k].pose = o.state.predicted;
            }
        }
    }
}

//! The places a re-detection search checks beyond the estimate's and the clusters' own: the best poses of a coarse
//! whole-pose search ([`crate::track::pose_search`]) over the orientations of
//! [`crate::track::RedetectConfig::pose_search_views`], at the estimate's place and at every cluster.

use crate::recon::DepthRig;
use crate::track::foreground_map::ForegroundMap;
use crate::track::object::ObjectModel;
use crate::track::pose_search::{
    DepthView, Hypothesis, HypothesisScoring, ShapeSamples, keep_best, orientation_lattice,
};
use crate::track::redetect::{Cluster, DepthBackground, RedetectConfig};
use drivers::recording::DepthFrame;
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};

/// Hypotheses kept from the first, coarse pass for the second, which also moves each sideways.
const FIRST_PASS_KEPT: usize = 12;
/// Samples scored per hypothesis in the first pass (a random subset: the samples are drawn at random).
const FIRST_PASS_SAMPLES: usize = 50;
/// How far the second pass moves a hypothesis across the line of sight, object diameters.
const SIDEWAYS_DIAMETERS: f64 = 0.15;

/// The whole-pose search: per object its surface samples, and the orientations tried.
pub(super) struct PoseSearch {
    shapes: Vec<ShapeSamples>,
    first_pass: Vec<ShapeSamples>,
    lattice: Vec<UnitQuaternion<f64>>,
    places: usize,
    pulls: usize,
    /// The way to the nearest foreground from every cell of the frame being searched.
    foreground: ForegroundMap,
    kept: Vec<Hypothesis>,
    best: Vec<Hypothesis>,
    residuals: Vec<f64>,
}

impl PoseSearch {
    /// The search over `shapes` (one per object) with the orientations and number of places of `cfg`.
    pub(super) fn new(cfg: &RedetectConfig, shapes: Vec<ShapeSamples>) -> Self {
        let lattice = orientation_lattice(cfg.pose_search_views, cfg.pose_search_rolls);
        let places = if lattice.is_empty() {
            0
        } else {
            cfg.pose_search_places
        };
        Self {
            first_pass: shapes
                .iter()
                .map(|s| s.prefix(FIRST_PASS_SAMPLES))
                .collect(),
            shapes,
            lattice,
            places,
            pulls: cfg.pose_search_pulls,
            foreground: ForegroundMap::default(),
            kept: Vec::with_capacity(FIRST_PASS_KEPT + 1),
            best: Vec::with_capacity(cfg.pose_search_places + 1),
            residuals: Vec::with_capacity(256),
        }
    }

    /// Reads the foreground `background` found in the frame about to be searched.
    pub(super) fn foreground_found(&mut self, background: &DepthBackground) {
        if self.enabled() && self.pulls > 0 {
            self.foreground.update(background);
        }
    }

    /// Whether the search tries any pose.
    pub(super) fn enabled(&self) -> bool {
        self.places > 0
    }

    /// The best poses of object `k` (`model`, estimated at `here`) on `frame`, at `here` and at each of
    /// `clusters`, in every orientation of the lattice and the estimated one: best first, into `out`.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn best_places(
        &mut self,
        k: usize,
        model: &ObjectModel,
        here: &Isometry3<f64>,
        clusters: &[Cluster],
        frame: &DepthFrame,
        rig: &DepthRig,
        background: &DepthBackground,
        scoring: &HypothesisScoring,
        out: &mut Vec<Isometry3<f64>>,
    ) {
        let (Some(shape), Some(first)) = (self.shapes.get(k), self.first_pass.get(k)) else {
            return;
        };
        if self.places == 0 || shape.len() == 0 {
            return;
        }
        let view = DepthView {
            frame,
            rig,
            background: Some(background),
        };
        let c = model.center_obj;
        let apart = (0.2 * model.diameter, 25f64.to_radians());
        let at = |rotation: UnitQuaternion<f64>, centre: &Point3<f64>| {
            Isometry3::from_parts(Translation3::from(centre.coords - rotation * c), rotation)
        };
        self.kept.clear();
        let step = SIDEWAYS_DIAMETERS * model.diameter;
        let offsets = |s: f64| {
            [
                Vector3::zeros(),
                Vector3::x() * s,
                -Vector3::x() * s,
                Vector3::y() * s,
                -Vector3::y() * s,
            ]
        };
        let centres =
            std::iter::once(model.center_at(here)).chain(clusters.iter().map(|c| c.centre));
        for centre in centres {
            for offset in offsets(2.0 * step) {
                for rotation in self.lattice.iter().copied().chain([here.rotation]) {
                    let h = view.score(
                        first,
                        &at(rotation, &(centre + offset)),
                        &c,
                        scoring,
                        &mut self.residuals,
                    );
                    keep_best(&mut self.kept, h, FIRST_PASS_KEPT, &c, apart);
                }
            }
        }
        self.best.clear();
        for h in &self.kept {
            let centre = h.pose * Point3::from(c);
            for offset in offsets(step) {
                let moved = at(h.pose.rotation, &(centre + offset));
                let scored = view.score(shape, &moved, &c, scoring, &mut self.residuals);
                keep_best(&mut self.best, scored, self.places, &c, apart);
            }
            if self.pulls > 0 {
                let mut pulled = h.pose;
                for _ in 0..self.pulls {
                    let Some(p) = view.pull_sideways(shape, &pulled, &self.foreground) else {
                        break;
                    };
                    pulled = view.score(shape, &p, &c, scoring, &mut self.residuals).pose;
                }
                let scored = view.score(shape, &pulled, &c, scoring, &mut self.residuals);
                keep_best(&mut self.best, scored, self.places, &c, apart);
            }
        }
        out.extend(self.best.iter().map(|h| h.pose));
    }
}

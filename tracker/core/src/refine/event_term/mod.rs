//! The event modality. The static background produces no events; the tracked object (its outline sweeping over
//! the background and its texture) does, and so do hands and other moving things.
//!
//! Default ([`EventTermKind::Lines`]): along each contour point's image normal, the events of the short window
//! `[t - dt, t]` (binned on the ROI grid, isolated bins removed) should change from "present" (inside: texture and
//! the band the outline swept) to "absent" (outside: background) at the outline. The step found on that line,
//! less the band a trailing edge leaves behind (predicted from the velocity), gives the residual; its contrast is
//! its weight, so a line with events on both sides (a holding hand) gives none. Before refining,
//! [`EventEdges::search_shift`] looks for the image shift of the whole outline that best separates events inside
//! from none outside, which reaches motions of a fast object (tens of pixels per tick) the residuals cannot.
//!
//! Alternative ([`EventTermKind::Hinge`]): events outside the silhouette contribute the hinge residual
//! `max(0, m . (e - pi(P)))` and contour points with no event under them are pulled in to the event cloud. It is
//! biased by events next to the object (see BENCHMARKS.md, "How the event term was chosen").
//!
//! Alternative ([`EventTermKind::ContrastMax`]): no residuals; the object velocity that sharpens the window's
//! events (lifted to 3D at the rendered depth) moves the previous estimate to the refinement's start. It measures
//! motion only and scored far below the lines on the dev suite.

mod bins;
mod contrast;
mod hinge;
mod lines;
mod search;
mod term;

pub use bins::BinnedWindow;
pub use term::{EventTerm, EventTermKind, EventTermStats};

use super::modality::Modality;
use super::model_view::ModelView;
use super::normal_equations::NormalEquations;
use crate::recon::EventSurface;
use bins::EventBins;
use contrast::ContrastMax;
use hinge::HingeMatches;
use lines::LineMatches;
use nalgebra::{Isometry3, Point3, Vector3, Vector6};
use scene::geometry::{PinholeCamera, Roi};
use search::ShiftSearch;

/// The event term's working state for one ROI: the binned events of the tick's window, how far each contour
/// point's motion swept it, and the matches and scratch of each kind of residual, reused from tick to tick.
#[derive(Debug, Clone, Default)]
pub struct EventEdges {
    bins: EventBins,
    /// Per contour point, how far (full-image pixels, along its outward normal) the predicted motion swept it
    /// during the event window: positive on leading edges, negative on trailing edges.
    sweep: Vec<f64>,
    hinge: HingeMatches,
    lines: LineMatches,
    search: ShiftSearch,
    contrast: ContrastMax,
    /// Residuals active in the latest accumulation.
    active: usize,
}

impl EventEdges {
    /// Statistics of the last collection / accumulation.
    pub fn stats(&self) -> EventTermStats {
        EventTermStats {
            bins: self.bins.kept_bins,
            outside: self.bins.outside,
            active: self.active,
        }
    }

    /// Bins the events of `surface` in `window` ahead of [`Self::collect`] (which reuses them if its call names the
    /// same window, and bins again otherwise): the part of the gathering that needs no render.
    pub fn bin_ahead(&mut self, surface: &EventSurface, window: BinnedWindow) {
        self.bins.bin_ahead(surface, window);
    }

    /// Forgets a binning made by [`Self::bin_ahead`] and returns its window, if any: the next
    /// [`Self::collect`] bins afresh unless given it back.
    pub fn take_prebinned(&mut self) -> Option<BinnedWindow> {
        self.bins.take_prebinned()
    }

    /// Bins the events of `surface` newer than `t_us - window_us` inside `roi` (the render's ROI; `mask` and
    /// `depth` are the render's mask and depth on the same grid, `id` the object's label) and keeps the candidates
    /// outside the silhouette. Events on another object's silhouette where it is nearer than `occluder_z` (metres,
    /// typically this object's centre depth) are that occluder's and are dropped; events on an object behind are
    /// kept, since this object's own leading edge sweeps over it. `prebinned` is the window a
    /// [`Self::bin_ahead`] binned (from [`Self::take_prebinned`]): if it is this one, its bins are used.
    #[allow(clippy::too_many_arguments)]
    pub fn collect(
        &mut self,
        term: &EventTerm,
        surface: &EventSurface,
        roi: &Roi,
        mask: &[u16],
        depth: &[f32],
        occluder_z: f32,
        id: u16,
        t_us: i64,
        window_us: i64,
        max_candidates: usize,
        prebinned: Option<BinnedWindow>,
    ) {
        self.hinge.reserve(max_candidates);
        self.active = 0;
        self.bins.collect(
            term,
            surface,
            roi,
            mask,
            depth,
            occluder_z,
            id,
            t_us,
            window_us,
            max_candidates,
            prebinned,
        );
    }

    /// Matches the events to `view`'s contour at `pose` as the term's kind needs: the outline step on each
    /// correspondence line, or the hinge's candidate and contour associations. `motion` is the object's
    /// predicted velocity (centre m/s, angular rad/s, camera frame) about `center_obj`, `window_s` the event window:
    /// together they say how wide a band of events each edge leaves behind.
    #[allow(clippy::too_many_arguments)]
    pub fn associate(
        &mut self,
        term: &EventTerm,
        view: &ModelView,
        pose: &Isometry3<f64>,
        center_obj: &Vector3<f64>,
        camera: &PinholeCamera,
        motion: &Vector6<f64>,
        window_s: f64,
    ) {
        self.sweep.clear();
        self.sweep.reserve(view.contour.capacity());
        let c = pose * Point3::from(*center_obj);
        let v = Vector3::new(motion[0], motion[1], motion[2]);
        let w = Vector3::new(motion[3], motion[4], motion[5]);
        for cp in &view.contour {
            let p = pose * cp.position;
            if p.z <= 0.01 {
                self.sweep.push(0.0);
                continue;
            }
            let dp = v + w.cross(&(p - c));
            let iz = 1.0 / p.z;
            let du = camera.fx * (dp.x - p.x * iz * dp.z) * iz;
            let dv = camera.fy * (dp.y - p.y * iz * dp.z) * iz;
            self.sweep
                .push((cp.normal_2d[0] * du + cp.normal_2d[1] * dv) * window_s);
        }
        self.lines.clear();
        match term.kind {
            // No residuals: the motion comes from `maximise_contrast`.
            EventTermKind::ContrastMax => {}
            EventTermKind::Lines => {
                self.lines
                    .find_steps(&self.bins, &self.sweep, term, view, pose, camera);
            }
            EventTermKind::Hinge => self.hinge.associate(&self.bins, term, view, pose, camera),
        }
    }

    /// Accumulates the event residuals of the term's kind at `pose` into `ne` (camera: the full event camera):
    /// the correspondence lines, or the hinge residuals of the associated candidates. Returns how many were
    /// active.
    pub fn accumulate(
        &mut self,
        term: &EventTerm,
        view: &ModelView,
        pose: &Isometry3<f64>,
        center_obj: &Vector3<f64>,
        camera: &PinholeCamera,
        ne: &mut NormalEquations,
    ) -> usize {
        self.active = match term.kind {
            EventTermKind::Lines => {
                self.lines
                    .accumulate(&self.sweep, term, view, pose, center_obj, camera, ne)
            }
            EventTermKind::ContrastMax => 0,
            EventTermKind::Hinge => self.hinge.accumulate(
                &self.bins,
                &self.sweep,
                term,
                view,
                pose,
                center_obj,
                camera,
                ne,
            ),
        };
        self.active
    }

    /// Fraction of `view`'s contour points at `pose` that have a kept event bin within two bins (event support of
    /// a moving outline); `None` without contour.
    pub fn contour_support(
        &self,
        view: &ModelView,
        pose: &Isometry3<f64>,
        camera: &PinholeCamera,
    ) -> Option<f64> {
        self.bins.contour_support(view, pose, camera)
    }

    /// Searches image shifts of `view`'s outline at `pose` (within the term's search range) for the one whose
    /// contour points best separate events inside from no events outside, up to `range_px` (full-image pixels).
    /// `motion_dir` is the unit image direction the object is predicted to move in, if known: near-best shifts
    /// are then told apart by how far they move the outline across it
    /// ([`EventTerm::search_aperture_tolerance`]). Returns the shift in full-image pixels if it beats the
    /// unshifted outline clearly, else `None`.
    pub fn search_shift(
        &mut self,
        term: &EventTerm,
        view: &ModelView,
        pose: &Isometry3<f64>,
        camera: &PinholeCamera,
        range_px: f64,
        motion_dir: Option<[f64; 2]>,
    ) -> Option<[f64; 2]> {
        self.search
            .search(&self.bins, term, view, pose, camera, range_px, motion_dir)
    }

    /// Lifts the kept events of the last [`Self::collect`] to 3D: each pixel's latest event in the window at the
    /// depth the render (`depth`, `mask` on the ROI grid, object `id`) has at its bin, or at `center_z` where the
    /// render shows no object. At most `max_events`, evenly strided.
    #[allow(clippy::too_many_arguments)]
    pub fn lift_events(
        &mut self,
        surface: &EventSurface,
        camera: &PinholeCamera,
        depth: &[f32],
        mask: &[u16],
        id: u16,
        t_us: i64,
        window_us: i64,
        center_z: f64,
        max_events: usize,
    ) {
        self.contrast.lift_events(
            &self.bins, surface, camera, depth, mask, id, t_us, window_us, center_z, max_events,
        );
    }

    /// The object velocity (centre m/s, angular rad/s, camera frame, about `center`) that maximises the contrast
    /// of the lifted events, found by a pattern search from `start` (steps halve `rounds` times). Returns `start`
    /// when there are no events.
    pub fn maximise_contrast(
        &mut self,
        camera: &PinholeCamera,
        center: &Point3<f64>,
        start: &Vector6<f64>,
        step_translation: f64,
        step_rotation: f64,
        rounds: u32,
    ) -> Vector6<f64> {
        self.contrast.maximise_contrast(
            &self.bins,
            camera,
            center,
            start,
            step_translation,
            step_rotation,
            rounds,
        )
    }

    /// Events lifted by the last [`Self::lift_events`].
    pub fn lifted_events(&self) -> usize {
        self.contrast.lifted_events()
    }
}

/// The event term as a [`Modality`] for one refinement: the outline against the events of the tick's window,
/// binned in [`EventEdges`], seen by the full event `camera`.
#[derive(Debug)]
pub struct EventModality<'a> {
    /// Whether it takes part in this refinement.
    pub active: bool,
    /// Parameters.
    pub term: &'a EventTerm,
    /// The binned events, matches and scratch.
    pub edges: &'a mut EventEdges,
    /// The full event camera.
    pub camera: &'a PinholeCamera,
    /// The object's predicted velocity (centre m/s, angular rad/s, camera frame) about `center_obj`.
    pub motion: &'a Vector6<f64>,
    /// The object's centre, object frame (the velocity's pivot).
    pub center_obj: &'a Vector3<f64>,
    /// The event window, seconds.
    pub window_s: f64,
    /// Scale of the term in the sum.
    pub weight: f64,
}

impl Modality for EventModality<'_> {
    fn name(&self) -> &'static str {
        "events"
    }

    fn is_active(&self) -> bool {
        self.active
    }

    fn weight(&self) -> f64 {
        self.weight
    }

    fn correspond(&mut self, view: &ModelView, pose: &Isometry3<f64>) {
        self.edges.associate(
            self.term,
            view,
            pose,
            self.center_obj,
            self.camera,
            self.motion,
            self.window_s,
        );
    }

    fn accumulate(
        &mut self,
        view: &ModelView,
        pose: &Isometry3<f64>,
        center_obj: &Vector3<f64>,
        ne: &mut NormalEquations,
    ) {
        self.edges
            .accumulate(self.term, view, pose, center_obj, self.camera, ne);
    }
}

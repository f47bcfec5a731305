//! Checking the places of a re-detection search: each place is a depth-only refinement from a start pose, done in
//! a scratch track of its own (a probe) and rendered with the other objects where they were at the frame's
//! exposure. A tick's checks are split over the tracker's renderers, one thread each, like the objects' steps;
//! every check reads only shared inputs and writes only its probe and its result, so the split changes nothing in
//! the results.

use super::renderers::Renderers;
use super::threads::{ShareRenderers, ShareSlice};
use crate::track::config::TrackerConfig;
use crate::track::object::{ObjectTrack, TickInputs};
use nalgebra::Isometry3;
use scene::geometry::PinholeCamera;
use scene::render::{RenderTarget, Renderer, Scene, SceneObject};

/// One place to check for one object.
#[derive(Debug, Clone, Copy)]
pub(super) struct PendingPlace {
    pub(super) object: usize,
    /// Start of the depth-only refinement, `T_cam_obj`.
    pub(super) start: Isometry3<f64>,
    /// Whether this is where the tracker estimated the object at the frame's exposure (the score to beat).
    pub(super) estimated: bool,
}

/// A checked place's score, in [0, 1], and the pose its refinement reached (`T_cam_obj`); `None` when nothing of
/// the object could be rendered or matched there.
pub(super) type PlaceResult = Option<(f64, Isometry3<f64>)>;

// The place checks hand probe sets and results to other threads through raw pointers: keep them `Send`.
const _: fn() = || {
    fn send<T: Send>() {}
    send::<ProbeSet>();
    send::<PlaceResult>();
};

/// One thread's scratch: a probe track per object and a copy of the scene to place it in.
pub(super) struct ProbeSet {
    probes: Vec<ObjectTrack>,
    scene: Vec<SceneObject>,
}

impl ProbeSet {
    /// Probes for `objects`, shown in `scene`.
    pub(super) fn new(
        objects: &[ObjectTrack],
        scene: &[SceneObject],
        config: &TrackerConfig,
    ) -> Self {
        Self {
            probes: objects.iter().map(|o| o.probe(config)).collect(),
            scene: scene.to_vec(),
        }
    }
}

/// What checking places against one depth frame needs (shared, read-only).
pub(super) struct PlaceCheck<'a> {
    /// The tracks, for each probe's motion state.
    pub(super) objects: &'a [ObjectTrack],
    /// Every object where it was at the frame's exposure.
    pub(super) scene: &'a [SceneObject],
    pub(super) camera: &'a PinholeCamera,
    pub(super) config: &'a TrackerConfig,
    /// The depth frame the places were planned on, at its exposure.
    pub(super) inputs: TickInputs<'a>,
}

impl PlaceCheck<'_> {
    /// Checks `places` in order into `results` (one each) with the probes of `set`; returns the failed renders.
    fn run(
        &self,
        places: &[PendingPlace],
        results: &mut [PlaceResult],
        set: &mut ProbeSet,
        renderer: &mut dyn Renderer,
    ) -> u64 {
        let mut errors = 0;
        for (place, result) in places.iter().zip(results) {
            *result = self.check(place, set, renderer, &mut errors);
        }
        errors
    }

    /// The object refined on the depth frame alone from the place's start, in its own ROI: the score (fraction of
    /// model points the depth confirms x sqrt of the silhouette's agreement with the depth at the object's range)
    /// and the refined pose.
    fn check(
        &self,
        place: &PendingPlace,
        set: &mut ProbeSet,
        renderer: &mut dyn Renderer,
        errors: &mut u64,
    ) -> PlaceResult {
        let k = place.object;
        let probe = set.probes.get_mut(k)?;
        probe.follow(self.objects.get(k)?);
        probe.state.predicted = place.start;
        set.scene.copy_from_slice(self.scene);
        set.scene[k].pose = place.start;
        let roi = probe.state.update_roi(
            &probe.model,
            self.camera,
            self.config,
            self.inputs.t_us,
            false,
        )?;
        let max_surface = self.config.correspond.max_surface_points;
        let mut render = |scene: &[SceneObject], target: &mut RenderTarget| {
            let scene = Scene::objects(scene)
                .geometry_only()
                .normals_on_surface_grid(max_surface);
            let ok = renderer
                .render_roi(&scene, self.camera, &roi, target)
                .is_ok();
            *errors += u64::from(!ok);
            ok
        };
        if !render(&set.scene, &mut probe.scratch.target) {
            return None;
        }
        let (fit, pose) = probe.probe_depth(&self.inputs, self.config)?;
        // Ranked by the silhouette at the refined pose, in the same ROI.
        set.scene[k].pose = pose;
        if !render(&set.scene, &mut probe.scratch.target) {
            return None;
        }
        // Both directions: model points the depth confirms, and depth at the object's range the model explains (a
        // pose showing a small part of the object can fit that part perfectly).
        Some((
            fit * probe.silhouette_agreement(&pose, self.config).sqrt(),
            pose,
        ))
    }

    /// [`Self::run`] over all `places`: split into one share per renderer, `renderer` checking the first share on
    /// this thread and each of `workers` one of the others on one of `threads`, each with its own probe set of
    /// `sets` (one per renderer). Returns the failed renders.
    pub(super) fn run_split(
        &self,
        places: &[PendingPlace],
        results: &mut [PlaceResult],
        sets: &mut [ProbeSet],
        renderers: &mut Renderers,
    ) -> u64 {
        let Renderers {
            main: renderer,
            workers,
            threads,
        } = renderers;
        let renderer = renderer.as_mut();
        if sets.is_empty() {
            return 0;
        }
        // Places with a result slot (the caller gives every place one).
        let len = places.len().min(results.len());
        let parts = (1 + workers.len().min(sets.len() - 1)).min(len);
        if parts <= 1 {
            return self.run(places, results, &mut sets[0], renderer);
        }
        let per_thread = len.div_ceil(parts);
        // At most `parts` shares, each starting below `len`, so share `i` has renderer `i` and probe set `i`.
        let shares = len.div_ceil(per_thread);
        let results = ShareSlice::new(results);
        let sets = ShareSlice::new(sets);
        let renderers = ShareRenderers::new(renderer, workers);
        threads.run(shares - 1, &|i| {
            let start = i * per_thread;
            let end = (start + per_thread).min(len);
            // SAFETY: share `i` takes `results[start..end]`, disjoint from the other shares' ranges, and probe set
            // `i` and renderer `i`, which no other share takes; `run` runs each share once.
            let (results, set, renderer) = unsafe {
                (
                    results.range(start..end),
                    &mut sets.range(i..i + 1)[0],
                    renderers.get(i),
                )
            };
            self.run(&places[start..end], results, set, renderer)
        })
    }
}

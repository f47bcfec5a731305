//! The tracker on a recording: building it from the recording's rig and models, and its benchmark methods
//! (`eventtrack6d`, `depth30`, `events-only`) behind [`crate::bench::Method`].

use super::method::{Method, MethodInput};
use crate::sequence::EvalError;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use scene::render::{CpuRenderer, Renderer};
use tracker::recording::{PoseRecord, recording_object, recording_rig};
use tracker::track::{
    EventTrack6d, OfflineTiming, TrackerConfig, TrackingMethod, track_recording_timed,
};

/// A first-pose perturbation: a rotation of `degrees` about a random axis and a translation of `centimetres` in a
/// random direction (seeded).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InitNoise {
    /// Rotation error, degrees.
    pub degrees: f64,
    /// Translation error, centimetres.
    pub centimetres: f64,
    /// Seed of the random directions.
    pub seed: u64,
}

impl InitNoise {
    /// Largest rotation error accepted, degrees (a turn by more is a turn by less the other way).
    pub const MAX_DEGREES: f64 = 180.0;
    /// Largest translation error accepted, centimetres (a first pose a metre off is not a tracking start).
    pub const MAX_CENTIMETRES: f64 = 100.0;

    /// Parses `DEG,CM` (e.g. `5,5`): DEG in [0, 180], CM in [0, 100].
    pub fn parse(text: &str, seed: u64) -> Result<Self, String> {
        let parts: Vec<&str> = text.split(',').map(str::trim).collect();
        let [deg, cm] = parts.as_slice() else {
            return Err(format!("init noise `{text}`: expected DEG,CM (e.g. 5,5)"));
        };
        let num = |s: &str, what: &str, max: f64| {
            let v = s
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite() && *v >= 0.0)
                .ok_or_else(|| format!("init noise `{text}`: {what} `{s}` is not a number >= 0"))?;
            if v > max {
                return Err(format!("init noise `{text}`: {what} `{s}` is over {max}"));
            }
            Ok(v)
        };
        Ok(Self {
            degrees: num(deg, "degrees", Self::MAX_DEGREES)?,
            centimetres: num(cm, "centimetres", Self::MAX_CENTIMETRES)?,
            seed,
        })
    }

    /// `pose` perturbed (rotation about the object's origin, in the camera frame).
    pub fn apply(&self, pose: &Isometry3<f64>) -> Isometry3<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        let mut unit = || loop {
            let v = Vector3::new(
                rng.random::<f64>() * 2.0 - 1.0,
                rng.random::<f64>() * 2.0 - 1.0,
                rng.random::<f64>() * 2.0 - 1.0,
            );
            let n = v.norm();
            if n > 1e-3 && n <= 1.0 {
                return v / n;
            }
        };
        let axis = unit();
        let dir = unit();
        let rotation =
            UnitQuaternion::from_scaled_axis(axis * self.degrees.to_radians()) * pose.rotation;
        let translation = pose.translation.vector + dir * self.centimetres / 100.0;
        Isometry3::from_parts(Translation3::from(translation), rotation)
    }
}

/// A benchmark method running the tracker with one of the method presets.
pub struct TrackerMethod {
    name: String,
    method: TrackingMethod,
    config: TrackerConfig,
    init_noise: Option<InitNoise>,
    /// Each depth frame reaches the tracker this long after its exposure, microseconds.
    depth_latency_us: i64,
    /// And up to this much more, drawn per frame, microseconds.
    depth_jitter_us: i64,
    renderer: Box<dyn Fn() -> Result<Box<dyn Renderer + Send>, String>>,
}

impl TrackerMethod {
    /// `method` with `base` parameters on the CPU renderer, no first-pose noise.
    pub fn new(method: TrackingMethod, base: &TrackerConfig) -> Self {
        Self {
            name: method.name().into(),
            method,
            config: method.configure(base),
            init_noise: None,
            depth_latency_us: 0,
            depth_jitter_us: 0,
            renderer: Box::new(|| Ok(Box::new(CpuRenderer::new()))),
        }
    }

    /// The parameters it tracks with (the base with the method's preset applied).
    pub fn config(&self) -> &TrackerConfig {
        &self.config
    }

    /// The same method with its first pose perturbed (report name gets a `@DEG,CM` suffix, and `,sSEED` for a
    /// seed other than 1; [`crate::seed_spread::seed_group`] reads it back).
    pub fn with_init_noise(mut self, noise: InitNoise) -> Self {
        self.name = format!(
            "{}@{},{}",
            self.method.name(),
            noise.degrees,
            noise.centimetres
        );
        if noise.seed != 1 {
            self.name = format!("{},s{}", self.name, noise.seed);
        }
        self.init_noise = Some(noise);
        self
    }

    /// The same method with each depth frame handed over `latency_us` microseconds after its exposure (at the
    /// first tick that late), as a live depth camera delivers it ([`OfflineTiming::depth_latency_us`]).
    pub fn with_depth_latency(mut self, latency_us: i64) -> Self {
        self.depth_latency_us = latency_us.max(0);
        self
    }

    /// The same method with each depth frame up to `jitter_us` microseconds later still, drawn per frame
    /// ([`OfflineTiming::depth_jitter_us`]).
    pub fn with_depth_jitter(mut self, jitter_us: i64) -> Self {
        self.depth_jitter_us = jitter_us.max(0);
        self
    }

    /// The same method rendering with renderers from `make`.
    pub fn with_renderer(
        mut self,
        make: impl Fn() -> Result<Box<dyn Renderer + Send>, String> + 'static,
    ) -> Self {
        self.renderer = Box::new(make);
        self
    }
}

impl Method for TrackerMethod {
    fn name(&self) -> &str {
        &self.name
    }

    fn parameters(&self) -> Option<serde_json::Value> {
        serde_json::to_value(&self.config).ok()
    }

    fn track(&mut self, input: &MethodInput<'_>) -> Result<Vec<PoseRecord>, EvalError> {
        let mut tracked = self.track_together(std::slice::from_ref(input))?;
        Ok(tracked.pop().unwrap_or_default())
    }

    /// Tracks all objects in one tracker, so that each sees the others' rendered silhouettes.
    fn track_together(
        &mut self,
        inputs: &[MethodInput<'_>],
    ) -> Result<Vec<Vec<PoseRecord>>, EvalError> {
        let Some(first_input) = inputs.first() else {
            return Ok(Vec::new());
        };
        let rec = first_input.recording;
        let model_error = |reason: String| EvalError::model(first_input.object, reason);
        let mut objects = Vec::with_capacity(inputs.len());
        for input in inputs {
            let (t0, gt0) = input.first_pose;
            let first = self.init_noise.map_or(gt0, |n| n.apply(&gt0));
            objects.push(recording_object(rec, input.object, t0, first)?);
        }
        let t0 = inputs.iter().map(|i| i.first_pose.0).min().unwrap_or(0);
        let renderer =
            (self.renderer)().map_err(|reason| model_error(format!("renderer: {reason}")))?;
        let mut tracker =
            EventTrack6d::new(self.config.clone(), recording_rig(rec)?, objects, renderer)
                .map_err(|e| model_error(e.to_string()))?;
        let mut out: Vec<Vec<PoseRecord>> = inputs
            .iter()
            .map(|i| Vec::with_capacity(i.ticks.len()))
            .collect();
        let timing = OfflineTiming {
            start_us: t0,
            depth_latency_us: self.depth_latency_us,
            depth_jitter_us: self.depth_jitter_us,
        };
        track_recording_timed(
            rec,
            &mut tracker,
            timing,
            |_, estimates, _| {
                for e in estimates {
                    if let (Some(poses), Some(input)) =
                        (out.get_mut(e.object), inputs.get(e.object))
                    {
                        poses.push(PoseRecord {
                            t_us: e.t_us,
                            object: input.object.to_string(),
                            pose: e.pose,
                            quality: f64::from(e.quality),
                            state: e.state.as_str().into(),
                        });
                    }
                }
            },
            |_| {},
        )?;
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn init_noise_text_is_two_numbers_at_least_zero() {
        let n = InitNoise::parse(" 5, 2.5 ", 7).expect("two numbers");
        assert_eq!((n.degrees, n.centimetres, n.seed), (5.0, 2.5, 7));
        for bad in [
            "5", "5,5,5", "-1,0", "x,1", "1,inf", "", "1,", "181,0", "0,100.5", "5,1e9",
        ] {
            let e = InitNoise::parse(bad, 0).expect_err(bad);
            assert!(e.contains(&format!("`{bad}`")), "{e}");
        }
    }

    proptest! {
        #[test]
        fn any_text_parses_or_says_why(text in "[0-9eE.,+ inf-]{0,12}", seed in any::<u64>()) {
            match InitNoise::parse(&text, seed) {
                Ok(n) => prop_assert!((0.0..=180.0).contains(&n.degrees) && (0.0..=100.0).contains(&n.centimetres)),
                Err(e) => prop_assert!(e.starts_with("init noise `"), "{}", e),
            }
        }

        /// The perturbed first pose is off by exactly the requested angle and distance, whatever the seed.
        #[test]
        fn the_perturbation_has_the_requested_size(
            degrees in 0.0f64..179.0,
            centimetres in 0.0f64..50.0,
            seed in any::<u64>(),
            t in prop::array::uniform3(-1.0f64..1.0),
            r in prop::array::uniform3(-3.0f64..3.0),
        ) {
            let pose = Isometry3::new(Vector3::from(t), Vector3::from(r));
            let noisy = InitNoise { degrees, centimetres, seed }.apply(&pose);
            prop_assert!((noisy.rotation.angle_to(&pose.rotation).to_degrees() - degrees).abs() < 1e-6);
            let moved = (noisy.translation.vector - pose.translation.vector).norm() * 100.0;
            prop_assert!((moved - centimetres).abs() < 1e-9);
        }
    }
}

//! What to generate (the object, its companions, motion, sensor parameters), the checks on it, and what a
//! generation reports or why it failed.

use crate::esim::{EsimConfig, EsimStats};
use crate::motion::{MotionProfile, SpeedLevel};
use crate::objects::ObjectKind;
use crate::objects::novel::{self, NovelFamily};
use drivers::recording::RecordingError;
use scene::render::RenderError;
use std::path::PathBuf;

/// Which object to put in the scene.
#[derive(Debug, Clone, PartialEq)]
pub enum ObjectSource {
    /// A procedural library object.
    Library(ObjectKind),
    /// A user OBJ (metres), copied into the recording with its MTL and textures.
    File(PathBuf),
    /// A procedurally generated object of a shape family the library lacks ([`crate::objects::novel`]), named
    /// `novel_<family>_<seed>`; mesh and texture depend on the family and this seed only, not on the recording's.
    Novel {
        /// Its shape family.
        family: NovelFamily,
        /// Its seed.
        seed: u64,
    },
}

impl ObjectSource {
    /// Reads an object given on the command line: a library name, `novel:SEED` or a novel object's name
    /// `novel_<family>_<seed>`, or a path ending in `.obj`.
    pub fn parse(name: &str) -> Option<Self> {
        if let Some(kind) = ObjectKind::from_name(name) {
            Some(ObjectSource::Library(kind))
        } else if let Some((family, seed)) = novel::parse_spec(name) {
            Some(ObjectSource::Novel { family, seed })
        } else if name.to_ascii_lowercase().ends_with(".obj") {
            Some(ObjectSource::File(PathBuf::from(name)))
        } else {
            None
        }
    }

    /// The object's name in the recording (models and ground truth); `None` for a user OBJ, which is named after
    /// its file.
    pub fn object_name(&self) -> Option<String> {
        match self {
            ObjectSource::Library(kind) => Some(kind.name().to_string()),
            ObjectSource::Novel { family, seed } => Some(novel::novel_name(*family, *seed)),
            ObjectSource::File(_) => None,
        }
    }
}

/// A further object in the scene, moving on its own trajectory (with its own hand) beside the first.
#[derive(Debug, Clone, PartialEq)]
pub struct Companion {
    /// The object.
    pub object: ObjectSource,
    /// Its motion profile.
    pub motion: MotionProfile,
    /// Its speed level.
    pub speed: SpeedLevel,
    /// Where its trajectory is centred relative to the first object's, metres, camera frame (negative z:
    /// nearer the camera, so it passes in front of the first object).
    pub offset_m: [f64; 3],
}

impl Companion {
    /// Parses a command-line companion `NAME[:MOTION[:SPEED[:X,Y,Z]]]` (library name, `novel:SEED`, a novel
    /// object's name or an `.obj` path; offset in metres). Motion and speed default to `motion` and `speed`; the
    /// offset to [`Self::default_offset`]`(k)`.
    pub fn parse(
        spec: &str,
        k: usize,
        motion: MotionProfile,
        speed: SpeedLevel,
    ) -> Result<Self, String> {
        let mut parts = spec.split(':');
        let mut name = parts.next().unwrap_or_default().trim().to_string();
        if name == "novel" {
            // `novel:SEED` holds the separator itself.
            name = format!("novel:{}", parts.next().unwrap_or_default().trim());
        }
        let Some(object) = ObjectSource::parse(&name) else {
            return Err(format!(
                "`{spec}`: unknown object `{name}` (a library name, novel:SEED, novel_<family>_<seed> or a path \
                 to an .obj file)"
            ));
        };
        let motion = match parts.next() {
            Some(m) => m.parse().map_err(|e| format!("`{spec}`: {e}"))?,
            None => motion,
        };
        let speed = match parts.next() {
            Some(v) => v.parse().map_err(|e| format!("`{spec}`: {e}"))?,
            None => speed,
        };
        let offset_m = match parts.next() {
            Some(o) => {
                let v: Vec<f64> = o
                    .split(',')
                    .map(|x| x.trim().parse::<f64>())
                    .collect::<Result<_, _>>()
                    .map_err(|e| format!("`{spec}`: offset `{o}`: {e}"))?;
                <[f64; 3]>::try_from(v)
                    .map_err(|_| format!("`{spec}`: offset `{o}` must be X,Y,Z in metres"))?
            }
            None => Self::default_offset(k),
        };
        if let Some(extra) = parts.next() {
            return Err(format!(
                "`{spec}`: unexpected `:{extra}` (NAME[:MOTION[:SPEED[:X,Y,Z]]])"
            ));
        }
        Ok(Self {
            object,
            motion,
            speed,
            offset_m,
        })
    }

    /// The offset of the `k`-th companion (from 1) when none is given: 15 cm nearer the camera per companion,
    /// so that each passes in front of the objects behind it as they move.
    pub fn default_offset(k: usize) -> [f64; 3] {
        [0.0, 0.0, -0.15 * k as f64]
    }
}

/// What to generate.
#[derive(Debug, Clone, PartialEq)]
pub struct GenerateConfig {
    /// The tracked object.
    pub object: ObjectSource,
    /// Further objects (each tracked too, and in the ground truth), empty by default.
    pub companions: Vec<Companion>,
    /// Motion profile.
    pub motion: MotionProfile,
    /// Speed level.
    pub speed: SpeedLevel,
    /// Length, seconds.
    pub seconds: f64,
    /// Seed of everything random (trajectory, textures, thresholds, noise).
    pub seed: u64,
    /// Event camera model.
    pub esim: EsimConfig,
    /// Probability that a depth frame is dropped.
    pub depth_drop_probability: f64,
    /// Whether hand-like occluders grip the object.
    pub hands: bool,
    /// Largest image motion of any object point between two renders, pixels (ESIM's adaptive sampling).
    pub max_step_px: f64,
}

impl GenerateConfig {
    /// A configuration with the simulator's defaults.
    pub fn new(
        object: ObjectSource,
        motion: MotionProfile,
        speed: SpeedLevel,
        seconds: f64,
        seed: u64,
    ) -> Self {
        Self {
            object,
            companions: Vec::new(),
            motion,
            speed,
            seconds,
            seed,
            esim: EsimConfig::default(),
            depth_drop_probability: 0.0,
            hands: true,
            max_step_px: 0.5,
        }
    }
}

/// What a generation produced.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct GenerateReport {
    /// Renders of the event camera's changing region.
    pub renders: u64,
    /// Mean rendered region, pixels.
    pub mean_region_px: f64,
    /// Event counters.
    pub esim: EsimStats,
    /// Trigger edges written.
    pub trigger_edges: u64,
    /// Depth frames written.
    pub depth_frames: u64,
    /// Depth frames dropped on purpose (the sensor model's frame drops).
    pub depth_frames_dropped: u64,
    /// Ground-truth rows written.
    pub ground_truth_rows: u64,
}

/// Why generation failed.
#[derive(Debug, thiserror::Error)]
pub enum GenerateError {
    /// A parameter is out of range.
    #[error("invalid parameter: {0}")]
    Parameter(String),
    /// The object or a prop could not be built or loaded.
    #[error(transparent)]
    Mesh(#[from] scene::mesh::MeshError),
    /// Writing the recording failed.
    #[error(transparent)]
    Recording(#[from] RecordingError),
    /// The renderer refused the scene.
    #[error("rendering failed: {0}")]
    Render(#[from] RenderError),
    /// A generation thread could not start or failed.
    #[error("{0}")]
    Thread(String),
    /// Copying a user mesh failed.
    #[error("{path}: {error}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        error: std::io::Error,
    },
}

/// Shortest sequence, seconds: long enough for the first 120 Hz ticks and the first depth frame, so the
/// recording can be opened and tracked.
pub const MIN_SECONDS: f64 = 0.01;

pub(super) fn check(config: &GenerateConfig) -> Result<(), GenerateError> {
    let bad = |s: &str| Err(GenerateError::Parameter(s.to_string()));
    if !(config.seconds.is_finite() && config.seconds >= MIN_SECONDS && config.seconds <= 600.0) {
        return bad(
            "seconds must be in [0.01, 600] (a recording needs its first ticks and depth frame)",
        );
    }
    if !(config.max_step_px.is_finite() && config.max_step_px > 0.01 && config.max_step_px <= 5.0) {
        return bad("max step must be in (0.01, 5] pixels");
    }
    if !(0.0..=1.0).contains(&config.depth_drop_probability) {
        return bad("depth frame drop probability must be in [0, 1]");
    }
    for (k, c) in config.companions.iter().enumerate() {
        let z = crate::motion::WORKING_DISTANCE_M + c.offset_m[2];
        if !(c.offset_m.iter().all(|v| v.is_finite() && v.abs() <= 1.0) && z >= 0.25) {
            return Err(GenerateError::Parameter(format!(
                "companion {} offset {:?} m: each coordinate must be within 1 m and the object at least 0.25 m \
                 from the camera",
                k + 1,
                c.offset_m
            )));
        }
    }
    let e = &config.esim;
    if e.contrast
        .is_some_and(|c| !(c.is_finite() && c > 0.01 && c < 2.0))
    {
        return bad("contrast threshold must be in (0.01, 2)");
    }
    if !(e.contrast_spread.is_finite() && e.contrast_spread >= 0.0) {
        return bad("contrast threshold spread must be >= 0");
    }
    if !(e.refractory_us.is_finite() && e.refractory_us >= 0.0) {
        return bad("refractory period must be >= 0 us");
    }
    if !(e.noise_rate_hz.is_finite() && (0.0..=100.0).contains(&e.noise_rate_hz)) {
        return bad("noise event rate (--noise-hz) must be in [0, 100] Hz per pixel");
    }
    if !(e.log_eps.is_finite() && e.log_eps > 0.0) {
        return bad("log intensity epsilon must be > 0");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Any `--with` text gives a companion or an error quoting it; it never panics.
        #[test]
        fn any_companion_text_parses_or_quotes_it(spec in "[a-z_.:,0-9 eE+-]{0,30}") {
            match Companion::parse(&spec, 1, MotionProfile::Shake, SpeedLevel::Slow) {
                Ok(c) => {
                    let name = spec.split(':').next().unwrap_or_default().trim();
                    match &c.object {
                        ObjectSource::Library(kind) => prop_assert_eq!(kind.name(), name),
                        ObjectSource::File(path) => prop_assert_eq!(path.to_str(), Some(name)),
                        ObjectSource::Novel { family, seed } => {
                            let parts: Vec<&str> = spec.split(':').map(str::trim).collect();
                            let named = novel::novel_name(*family, *seed) == name;
                            let by_seed = name == "novel"
                                && parts.get(1).and_then(|p| p.parse::<u64>().ok()) == Some(*seed);
                            prop_assert!(named || by_seed, "{:?}", c.object);
                        }
                    }
                }
                Err(e) => prop_assert!(e.starts_with(&format!("`{spec}`: ")), "{}", e),
            }
        }

        /// A companion written out in full reads back as itself.
        #[test]
        fn a_written_companion_reads_back(
            kind in proptest::sample::select(ObjectKind::ALL.to_vec()),
            motion in proptest::sample::select(MotionProfile::ALL.to_vec()),
            speed in proptest::sample::select(SpeedLevel::ALL.to_vec()),
            offset in proptest::array::uniform3(-1.0f64..1.0),
        ) {
            let spec = format!(
                "{}:{}:{}:{},{},{}",
                kind.name(), motion.name(), speed.name(), offset[0], offset[1], offset[2]
            );
            let c = Companion::parse(&spec, 3, MotionProfile::Shake, SpeedLevel::Slow)
                .map_err(TestCaseError::fail)?;
            prop_assert_eq!(c, Companion { object: ObjectSource::Library(kind), motion, speed, offset_m: offset });
        }
    }

    #[test]
    fn companion_specs_parse_with_defaults_and_name_what_is_wrong() {
        let (m, s) = (MotionProfile::Shake, SpeedLevel::Slow);
        let c = Companion::parse("can", 2, m, s).unwrap();
        assert_eq!(c.object, ObjectSource::Library(ObjectKind::Can));
        assert_eq!((c.motion, c.speed), (m, s));
        assert_eq!(c.offset_m, [0.0, 0.0, -0.3]);
        let c = Companion::parse("bowl:hand-switch:fast:0.05,-0.02,-0.1", 1, m, s).unwrap();
        assert_eq!(c.object, ObjectSource::Library(ObjectKind::Bowl));
        assert_eq!(
            (c.motion, c.speed),
            (MotionProfile::HandSwitch, SpeedLevel::Fast)
        );
        assert_eq!(c.offset_m, [0.05, -0.02, -0.1]);
        let c = Companion::parse("parts/gear.obj:rotation", 1, m, s).unwrap();
        assert_eq!(c.object, ObjectSource::File("parts/gear.obj".into()));
        assert_eq!(c.motion, MotionProfile::Rotation);
        let c = Companion::parse("novel:7001:throw", 1, m, s).unwrap();
        assert_eq!(
            c.object,
            ObjectSource::Novel {
                family: NovelFamily::for_seed(7001),
                seed: 7001
            }
        );
        assert_eq!(c.motion, MotionProfile::ThrowCatch);
        let c = Companion::parse("novel_torus_17:shake:fast", 1, m, s).unwrap();
        assert_eq!(
            c.object,
            ObjectSource::Novel {
                family: NovelFamily::Torus,
                seed: 17
            }
        );
        assert_eq!(c.speed, SpeedLevel::Fast);
        for (spec, needle) in [
            ("teapot", "unknown object `teapot`"),
            ("novel:x:shake", "unknown object `novel:x`"),
            ("novel_cube_3", "unknown object `novel_cube_3`"),
            ("can:wobble", "unknown motion profile `wobble`"),
            ("can:shake:warp", "unknown speed level `warp`"),
            ("can:shake:slow:1,2", "must be X,Y,Z"),
            ("can:shake:slow:1,x,2", "offset `1,x,2`"),
            ("can:shake:slow:0,0,0:more", "unexpected `:more`"),
        ] {
            let e = Companion::parse(spec, 1, m, s).unwrap_err();
            assert!(e.contains(needle) && e.contains(spec), "{spec}: {e}");
        }
    }
}

//! The recording directory (DESIGN section 9; documented in `docs/recording-format.md`):
//!
//! ```text
//! REC/events.raw              EVT 3.0 with trigger words
//! REC/depth/NNNNNN.png        16-bit depth in millimetres, N = depth frame number
//! REC/camera.json             both cameras and T_event_depth
//! REC/groundtruth.csv         t_us,object,x,y,z,qx,qy,qz,qw (optional: absent on real recordings)
//! REC/models/models_info.json BOP-style, keyed by object name; meshes models/<name>.obj (+ .mtl, texture)
//! REC/meta.json               what produced it, and the trigger schedule
//! ```

mod camera;
mod depth;
mod groundtruth;
mod models;
mod writer;

pub use camera::{CameraIntrinsics, CameraRig};
pub use depth::{DepthFrame, depth_png_size, read_depth_png, write_depth_png};
pub use groundtruth::{GROUND_TRUTH_HEADER, PoseSample, format_ground_truth, parse_ground_truth};
pub use models::{ContinuousSymmetry, ModelInfo, models_info_json, parse_models_info};
pub use writer::RecordingWriter;

use crate::raw::{RawHeader, RawReader};
use crate::timeline::TimelineConfig;
use serde::{Deserialize, Serialize};
use std::fs::File;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// A recording that cannot be opened or read: names the file and the problem.
#[derive(Debug, Error)]
#[error("{}: {problem}", path.display())]
pub struct RecordingError {
    /// The offending file or directory.
    pub path: PathBuf,
    /// What is wrong.
    pub problem: String,
}

impl RecordingError {
    fn new(path: impl Into<PathBuf>, problem: impl Into<String>) -> Self {
        Self {
            path: path.into(),
            problem: problem.into(),
        }
    }
}

/// The trigger schedule as stored in `meta.json` (see [`TimelineConfig`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TriggerSchedule {
    /// Trigger input channel.
    pub channel: u8,
    /// Tick rate, Hz.
    pub tick_rate_hz: f64,
    /// Ticks per depth exposure.
    pub ticks_per_depth: u32,
    /// Ordinary pulse width, microseconds.
    pub narrow_width_us: i64,
    /// Phase-coded (depth-exposure) pulse width, microseconds.
    pub wide_width_us: i64,
}

impl Default for TriggerSchedule {
    fn default() -> Self {
        let c = TimelineConfig::default();
        Self {
            channel: c.channel,
            tick_rate_hz: c.tick_rate_hz,
            ticks_per_depth: c.ticks_per_depth,
            narrow_width_us: c.narrow_width_us,
            wide_width_us: c.wide_width_us,
        }
    }
}

impl TriggerSchedule {
    /// Why this schedule cannot drive a timeline, if it cannot: a tick rate that is not a positive number up to
    /// 10 kHz, no ticks per depth exposure, an event channel over 15 (EVT 3.0 carries 0..=15), or pulse widths
    /// that are not positive with the phase-coded one wider.
    pub fn problem(&self) -> Option<String> {
        if !(self.tick_rate_hz.is_finite()
            && self.tick_rate_hz > 0.0
            && self.tick_rate_hz <= 10_000.0)
        {
            return Some(format!(
                "trigger.tick_rate_hz {} is not in (0, 10000]",
                self.tick_rate_hz
            ));
        }
        if self.ticks_per_depth == 0 {
            return Some(
                "trigger.ticks_per_depth is 0 (120 Hz ticks per 30 Hz depth frame: 4)".into(),
            );
        }
        if self.channel > 15 {
            return Some(format!(
                "trigger.channel {} is over 15 (EVT 3.0 carries channels 0..15)",
                self.channel
            ));
        }
        if self.narrow_width_us <= 0 || self.wide_width_us <= self.narrow_width_us {
            return Some(format!(
                "trigger pulse widths {} / {} us: both must be positive, the phase-coded (wide) one the wider",
                self.narrow_width_us, self.wide_width_us
            ));
        }
        None
    }

    /// The timeline configuration for this schedule (default jitter tolerance).
    pub fn timeline_config(&self) -> TimelineConfig {
        TimelineConfig {
            channel: self.channel,
            tick_rate_hz: self.tick_rate_hz,
            ticks_per_depth: self.ticks_per_depth,
            narrow_width_us: self.narrow_width_us,
            wide_width_us: self.wide_width_us,
            ..TimelineConfig::default()
        }
    }
}

/// `meta.json`: what produced the recording, plus free-form generator parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RecordingMeta {
    /// Producer and version, e.g. `hil-sim 0.1.0` or `eventtrack6d record 0.1.0`.
    pub generator: String,
    /// The trigger schedule the events carry.
    #[serde(default)]
    pub trigger: TriggerSchedule,
    /// Generator parameters (seed, motion profile, ...), kept as given.
    #[serde(default)]
    pub parameters: serde_json::Map<String, serde_json::Value>,
}

/// An opened, checked recording. Large data (events, depth images) is read on demand.
#[derive(Debug, Clone)]
pub struct Recording {
    dir: PathBuf,
    /// Cameras and extrinsics.
    pub rig: CameraRig,
    /// Producer and trigger schedule.
    pub meta: RecordingMeta,
    /// Object models, sorted by name.
    pub models: Vec<ModelInfo>,
    /// Ground-truth poses in file order, if the recording has them.
    pub ground_truth: Option<Vec<PoseSample>>,
    /// Depth frame numbers present on disk, ascending.
    pub depth_frames: Vec<u64>,
    /// Header of `events.raw`.
    pub events_header: RawHeader,
}

impl Recording {
    /// Opens `dir` and checks it for consistency: every required file present and parseable, event geometry
    /// equal to the event camera's resolution, every depth image 16-bit at the depth camera's resolution,
    /// ground truth ordered in time and naming only known objects, every model's mesh present.
    pub fn open(dir: &Path) -> Result<Self, RecordingError> {
        if !dir.is_dir() {
            return Err(RecordingError::new(
                dir,
                "is not a recording directory (not a directory)",
            ));
        }
        let rig: CameraRig = read_json(&dir.join("camera.json"))?;
        rig.validate()
            .map_err(|p| RecordingError::new(dir.join("camera.json"), p))?;
        let meta: RecordingMeta = read_json(&dir.join("meta.json"))?;
        if let Some(problem) = meta.trigger.problem() {
            return Err(RecordingError::new(dir.join("meta.json"), problem));
        }

        let info_path = dir.join("models").join("models_info.json");
        let models = parse_models_info(&read_text(&info_path)?)
            .map_err(|p| RecordingError::new(&info_path, p))?;
        if models.is_empty() {
            return Err(RecordingError::new(&info_path, "lists no objects"));
        }
        for m in &models {
            let mesh = dir.join("models").join(format!("{}.obj", m.name));
            if !mesh.is_file() {
                return Err(RecordingError::new(
                    mesh,
                    format!("mesh of object `{}` is missing", m.name),
                ));
            }
        }

        let events_path = dir.join("events.raw");
        let reader = RawReader::open(&events_path)
            .map_err(|e| RecordingError::new(&events_path, e.problem()))?;
        let events_header = reader.header().clone();
        let (ew, eh) = (rig.event_camera.width, rig.event_camera.height);
        match events_header.geometry {
            Some(g) if (u32::from(g.width), u32::from(g.height)) == (ew, eh) => {}
            Some(g) => {
                return Err(RecordingError::new(
                    &events_path,
                    format!(
                        "geometry {}x{} differs from camera.json event_camera {ew}x{eh}",
                        g.width, g.height
                    ),
                ));
            }
            None => {
                return Err(RecordingError::new(
                    &events_path,
                    "header gives no sensor geometry",
                ));
            }
        }

        let depth_frames = scan_depth_dir(&dir.join("depth"), &rig.depth_camera)?;

        let gt_path = dir.join("groundtruth.csv");
        let ground_truth = if gt_path.exists() {
            let poses = parse_ground_truth(&read_text(&gt_path)?)
                .map_err(|p| RecordingError::new(&gt_path, p))?;
            if let Some(p) = poses
                .iter()
                .find(|p| !models.iter().any(|m| m.name == p.object))
            {
                return Err(RecordingError::new(
                    &gt_path,
                    format!("object `{}` is not in models/models_info.json", p.object),
                ));
            }
            Some(poses)
        } else {
            None
        };
        Ok(Self {
            dir: dir.to_path_buf(),
            rig,
            meta,
            models,
            ground_truth,
            depth_frames,
            events_header,
        })
    }

    /// The recording directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// A fresh streaming reader over `events.raw`.
    pub fn events(&self) -> Result<RawReader<File>, RecordingError> {
        let p = self.dir.join("events.raw");
        RawReader::open(&p).map_err(|e| RecordingError::new(&p, e.problem()))
    }

    /// Path of depth frame `index` (whether or not it exists).
    pub fn depth_path(&self, index: u64) -> PathBuf {
        self.dir.join("depth").join(format!("{index:06}.png"))
    }

    /// Reads depth frame `index` in metres. A frame absent from disk (dropped) is an error naming it.
    pub fn depth_frame(&self, index: u64) -> Result<DepthFrame, RecordingError> {
        let p = self.depth_path(index);
        let (width, height, units) = read_depth_png(&p).map_err(|e| RecordingError::new(&p, e))?;
        let (dw, dh) = (self.rig.depth_camera.width, self.rig.depth_camera.height);
        if (width, height) != (dw, dh) {
            return Err(RecordingError::new(
                &p,
                format!("image is {width}x{height}, camera.json says {dw}x{dh}"),
            ));
        }
        let s = self.rig.depth_scale_m as f32;
        Ok(DepthFrame {
            index,
            width,
            height,
            depth_m: units.iter().map(|&u| f32::from(u) * s).collect(),
        })
    }

    /// Depth frame numbers between the first and last present that are missing on disk (dropped frames).
    pub fn dropped_depth_frames(&self) -> Vec<u64> {
        let mut out = Vec::new();
        for w in self.depth_frames.windows(2) {
            out.extend(w[0] + 1..w[1]);
        }
        out
    }

    /// Path of the mesh of `object`.
    pub fn mesh_path(&self, object: &str) -> PathBuf {
        self.dir.join("models").join(format!("{object}.obj"))
    }

    /// The model named `object`.
    pub fn model(&self, object: &str) -> Option<&ModelInfo> {
        self.models.iter().find(|m| m.name == object)
    }
}

fn read_text(path: &Path) -> Result<String, RecordingError> {
    std::fs::read_to_string(path).map_err(|e| {
        let problem = if e.kind() == std::io::ErrorKind::NotFound {
            "is missing".to_string()
        } else {
            e.to_string()
        };
        RecordingError::new(path, problem)
    })
}

fn read_json<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T, RecordingError> {
    serde_json::from_str(&read_text(path)?)
        .map_err(|e| RecordingError::new(path, format!("invalid: {e}")))
}

fn scan_depth_dir(dir: &Path, cam: &CameraIntrinsics) -> Result<Vec<u64>, RecordingError> {
    let entries = std::fs::read_dir(dir).map_err(|e| {
        let problem = if e.kind() == std::io::ErrorKind::NotFound {
            "is missing".to_string()
        } else {
            e.to_string()
        };
        RecordingError::new(dir, problem)
    })?;
    let mut frames = Vec::new();
    for entry in entries {
        let entry = entry.map_err(|e| RecordingError::new(dir, e.to_string()))?;
        let path = entry.path();
        let name = entry.file_name().to_string_lossy().into_owned();
        let index = name
            .strip_suffix(".png")
            .filter(|s| s.len() >= 6 && s.bytes().all(|b| b.is_ascii_digit()))
            .and_then(|s| s.parse::<u64>().ok())
            .ok_or_else(|| {
                RecordingError::new(&path, "unexpected file: depth images are named NNNNNN.png")
            })?;
        let (w, h) = depth_png_size(&path).map_err(|p| RecordingError::new(&path, p))?;
        if (w, h) != (cam.width, cam.height) {
            return Err(RecordingError::new(
                &path,
                format!(
                    "image is {w}x{h}, camera.json depth_camera is {}x{}",
                    cam.width, cam.height
                ),
            ));
        }
        frames.push(index);
    }
    if frames.is_empty() {
        return Err(RecordingError::new(dir, "holds no depth images"));
    }
    frames.sort_unstable();
    Ok(frames)
}

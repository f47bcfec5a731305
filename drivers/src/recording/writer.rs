//! Writing a recording directory.

use super::{
    CameraRig, ModelInfo, PoseSample, RecordingError, RecordingMeta, format_ground_truth,
    models_info_json, write_depth_png,
};
use crate::event::{CdEvent, Geometry, TriggerEdge};
use crate::formats::any::EventFormat;
use crate::raw::{RawHeader, RawWriter};
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

/// Writes a recording: events stream in as they are produced, depth frames one by one, the rest at `finish`.
/// Meshes are written by the caller into [`models_dir`](Self::models_dir).
pub struct RecordingWriter {
    dir: PathBuf,
    rig: CameraRig,
    events: RawWriter<BufWriter<File>>,
}

impl RecordingWriter {
    /// Creates `dir` (and `depth/`, `models/`) and starts `events.raw` (EVT 3.0 at the event camera's size).
    pub fn create(dir: &Path, rig: CameraRig, generator: &str) -> Result<Self, RecordingError> {
        rig.validate()
            .map_err(|p| RecordingError::new(dir.join("camera.json"), p))?;
        for d in [dir.to_path_buf(), dir.join("depth"), dir.join("models")] {
            std::fs::create_dir_all(&d).map_err(|e| RecordingError::new(&d, e.to_string()))?;
        }
        let (w, h) = (rig.event_camera.width, rig.event_camera.height);
        let geometry = match (u16::try_from(w), u16::try_from(h)) {
            (Ok(w), Ok(h)) if w <= 2048 && h <= 2048 => Geometry::new(w, h),
            _ => {
                return Err(RecordingError::new(
                    dir.join("camera.json"),
                    "event camera larger than 2048x2048",
                ));
            }
        };
        let header = RawHeader::new(EventFormat::Evt3, geometry, &[("generator", generator)]);
        let p = dir.join("events.raw");
        let file = File::create(&p).map_err(|e| RecordingError::new(&p, e.to_string()))?;
        let events = RawWriter::new(BufWriter::with_capacity(1 << 20, file), &header)
            .map_err(|e| RecordingError::new(&p, e.to_string()))?;
        Ok(Self {
            dir: dir.to_path_buf(),
            rig,
            events,
        })
    }

    /// Directory for meshes and textures.
    pub fn models_dir(&self) -> PathBuf {
        self.dir.join("models")
    }

    /// Appends time-ordered events and trigger edges to `events.raw`.
    pub fn write_events(
        &mut self,
        cd: &[CdEvent],
        triggers: &[TriggerEdge],
    ) -> Result<(), RecordingError> {
        self.events
            .write(cd, triggers)
            .map_err(|e| RecordingError::new(self.dir.join("events.raw"), e.to_string()))
    }

    /// Writes depth frame `index` given in millimetres (0 = invalid) at the depth camera's resolution.
    pub fn write_depth_mm(&mut self, index: u64, depth_mm: &[u16]) -> Result<(), RecordingError> {
        let p = self.dir.join("depth").join(format!("{index:06}.png"));
        let (w, h) = (self.rig.depth_camera.width, self.rig.depth_camera.height);
        write_depth_png(&p, w, h, depth_mm).map_err(|e| RecordingError::new(&p, e))
    }

    /// Writes `camera.json`, `meta.json`, `models/models_info.json` and (if given) `groundtruth.csv`, and
    /// closes `events.raw`.
    pub fn finish(
        self,
        meta: &RecordingMeta,
        models: &[ModelInfo],
        ground_truth: Option<&[PoseSample]>,
    ) -> Result<(), RecordingError> {
        let p = self.dir.join("events.raw");
        self.events
            .finish()
            .map_err(|e| RecordingError::new(&p, e.to_string()))?;
        let write = |name: &Path, text: String| {
            std::fs::write(name, text).map_err(|e| RecordingError::new(name, e.to_string()))
        };
        write(&self.dir.join("camera.json"), pretty_json(&self.rig))?;
        write(&self.dir.join("meta.json"), pretty_json(meta))?;
        write(
            &self.dir.join("models").join("models_info.json"),
            models_info_json(models),
        )?;
        if let Some(gt) = ground_truth {
            write(&self.dir.join("groundtruth.csv"), format_ground_truth(gt))?;
        }
        Ok(())
    }
}

/// Pretty JSON of plain data (maps with string keys and finite numbers cannot fail to serialise).
fn pretty_json<T: serde::Serialize>(value: &T) -> String {
    serde_json::to_string_pretty(value).unwrap_or_default()
}

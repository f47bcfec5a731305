//! A tracked object of a recording: its mesh from `models/`, its diameter and symmetries from
//! `models_info.json`, and its first pose.

use super::SetupError;
use super::symmetry::symmetries_of;
use crate::track::TrackedObject;
use drivers::recording::Recording;
use nalgebra::Isometry3;
use scene::mesh::{MeshLoadOptions, load_obj};
use std::sync::Arc;

/// The tracked object `name` of a recording (mesh from `models/`, diameter from `models_info.json`) with its first
/// pose.
pub fn recording_object(
    rec: &Recording,
    name: &str,
    first_t_us: i64,
    first_pose: Isometry3<f64>,
) -> Result<TrackedObject, SetupError> {
    let info = rec.model(name).ok_or_else(|| SetupError::Model {
        object: name.into(),
        reason: "not listed in models/models_info.json".into(),
    })?;
    let loaded = load_obj(&rec.mesh_path(name), &MeshLoadOptions::default()).map_err(|e| {
        SetupError::Model {
            object: name.into(),
            reason: e.to_string(),
        }
    })?;
    Ok(TrackedObject {
        name: name.into(),
        mesh: Arc::new(loaded.mesh),
        diameter: info.diameter_m,
        first_t_us,
        first_pose,
        symmetries: symmetries_of(info)?,
    })
}

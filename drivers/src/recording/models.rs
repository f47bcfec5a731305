//! `models/models_info.json`: BOP-style object information, keyed by object name.
//!
//! As in the BOP toolkit the file stores millimetres (`diameter`, `min_*`, `size_*`, the translation column of
//! `symmetries_discrete`, continuous-symmetry `offset`); in memory everything is metres.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// A continuous rotational symmetry: any rotation about `axis` through `offset_m` leaves the model unchanged.
#[derive(Debug, Clone, PartialEq)]
pub struct ContinuousSymmetry {
    /// Unit axis in the model frame.
    pub axis: [f64; 3],
    /// A point on the axis, metres, model frame.
    pub offset_m: [f64; 3],
}

/// What the tracker and the metrics need to know about one object model.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelInfo {
    /// Object name; the mesh is `models/<name>.obj`.
    pub name: String,
    /// Largest distance between two model points, metres.
    pub diameter_m: f64,
    /// Bounding-box minimum corner, metres, model frame.
    pub min_m: [f64; 3],
    /// Bounding-box size, metres.
    pub size_m: [f64; 3],
    /// Discrete symmetries as row-major 4x4 transforms (translation in metres).
    pub symmetries_discrete: Vec<[f64; 16]>,
    /// Continuous symmetries.
    pub symmetries_continuous: Vec<ContinuousSymmetry>,
}

#[derive(Debug, Serialize, Deserialize)]
struct BopContinuous {
    axis: [f64; 3],
    offset: [f64; 3],
}

#[derive(Debug, Serialize, Deserialize)]
struct BopModelInfo {
    diameter: f64,
    min_x: f64,
    min_y: f64,
    min_z: f64,
    size_x: f64,
    size_y: f64,
    size_z: f64,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    symmetries_discrete: Vec<[f64; 16]>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    symmetries_continuous: Vec<BopContinuous>,
}

/// Parses `models_info.json` text; errors name the object and field.
pub fn parse_models_info(text: &str) -> Result<Vec<ModelInfo>, String> {
    let raw: BTreeMap<String, BopModelInfo> =
        serde_json::from_str(text).map_err(|e| e.to_string())?;
    let mut out = Vec::with_capacity(raw.len());
    for (name, b) in raw {
        if name.is_empty() || name.contains(['/', '\\', ',']) || name.starts_with('.') {
            return Err(format!(
                "object name `{name}` is not usable as a file name / CSV field"
            ));
        }
        if !(b.diameter.is_finite() && b.diameter > 0.0) {
            return Err(format!(
                "object `{name}`: diameter {} must be positive (millimetres)",
                b.diameter
            ));
        }
        let all = [b.min_x, b.min_y, b.min_z, b.size_x, b.size_y, b.size_z];
        if all.iter().any(|v| !v.is_finite()) || b.size_x < 0.0 || b.size_y < 0.0 || b.size_z < 0.0
        {
            return Err(format!(
                "object `{name}`: bounding box must be finite with non-negative sizes"
            ));
        }
        let mut discrete = Vec::with_capacity(b.symmetries_discrete.len());
        for (i, m) in b.symmetries_discrete.iter().enumerate() {
            if m.iter().any(|v| !v.is_finite()) || m[12..] != [0.0, 0.0, 0.0, 1.0] {
                return Err(format!(
                    "object `{name}`: symmetries_discrete[{i}] is not a finite rigid 4x4 matrix"
                ));
            }
            let mut s = *m;
            for k in [3, 7, 11] {
                s[k] *= 1e-3;
            }
            discrete.push(s);
        }
        let mut continuous = Vec::with_capacity(b.symmetries_continuous.len());
        for (i, c) in b.symmetries_continuous.iter().enumerate() {
            let n = (c.axis[0].powi(2) + c.axis[1].powi(2) + c.axis[2].powi(2)).sqrt();
            if !(n.is_finite() && n > 1e-9) || c.offset.iter().any(|v| !v.is_finite()) {
                return Err(format!(
                    "object `{name}`: symmetries_continuous[{i}] needs a non-zero finite axis"
                ));
            }
            continuous.push(ContinuousSymmetry {
                axis: [c.axis[0] / n, c.axis[1] / n, c.axis[2] / n],
                offset_m: [c.offset[0] * 1e-3, c.offset[1] * 1e-3, c.offset[2] * 1e-3],
            });
        }
        out.push(ModelInfo {
            name,
            diameter_m: b.diameter * 1e-3,
            min_m: [b.min_x * 1e-3, b.min_y * 1e-3, b.min_z * 1e-3],
            size_m: [b.size_x * 1e-3, b.size_y * 1e-3, b.size_z * 1e-3],
            symmetries_discrete: discrete,
            symmetries_continuous: continuous,
        });
    }
    Ok(out)
}

/// Serialises models to `models_info.json` text (millimetres, BOP keys).
pub fn models_info_json(models: &[ModelInfo]) -> String {
    let map: BTreeMap<&str, BopModelInfo> = models
        .iter()
        .map(|m| {
            let mm = |v: f64| v * 1e3;
            let b = BopModelInfo {
                diameter: mm(m.diameter_m),
                min_x: mm(m.min_m[0]),
                min_y: mm(m.min_m[1]),
                min_z: mm(m.min_m[2]),
                size_x: mm(m.size_m[0]),
                size_y: mm(m.size_m[1]),
                size_z: mm(m.size_m[2]),
                symmetries_discrete: m
                    .symmetries_discrete
                    .iter()
                    .map(|s| {
                        let mut s = *s;
                        for k in [3, 7, 11] {
                            s[k] *= 1e3;
                        }
                        s
                    })
                    .collect(),
                symmetries_continuous: m
                    .symmetries_continuous
                    .iter()
                    .map(|c| BopContinuous {
                        axis: c.axis,
                        offset: c.offset_m.map(mm),
                    })
                    .collect(),
            };
            (m.name.as_str(), b)
        })
        .collect();
    serde_json::to_string_pretty(&map).unwrap_or_else(|_| "{}".into())
}

//! Object information in the shape of BOP's `models_info.json`: diameter, extent and symmetries.
//!
//! In memory everything is in metres; the BOP JSON shape uses millimetres (as BOP does).

use super::{Aabb, Mesh};
use nalgebra::{
    Isometry3, Matrix3, Matrix4, Point3, Rotation3, Translation3, Unit, UnitQuaternion, Vector3,
};
use serde_json::{Value, json};

/// A shape symmetry of an object, in the object frame: transforms under which the model looks the same.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Symmetry {
    /// A single rigid transform (e.g. a 180 degree turn of a box), translation in metres. Identity is implied and
    /// should not be listed.
    Discrete(Isometry3<f64>),
    /// Any rotation about `axis` through the point `offset` (metres), e.g. a can or a bowl.
    Continuous {
        /// Rotation axis, unit, object frame.
        axis: Unit<Vector3<f64>>,
        /// A point on the axis, metres.
        offset: Point3<f64>,
    },
}

/// Per-object information (BOP `models_info` entry), in metres.
#[derive(Debug, Clone, PartialEq)]
pub struct ObjectInfo {
    /// Diameter (largest vertex-to-vertex distance), metres.
    pub diameter: f64,
    /// Axis-aligned bounding box in the object frame, metres.
    pub aabb: Aabb,
    /// Shape symmetries (identity excluded).
    pub symmetries: Vec<Symmetry>,
}

/// Why a BOP `models_info` entry could not be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("invalid models_info entry for {object}: {reason}")]
pub struct ObjectInfoError {
    /// Which object (its key in models_info.json, or a description).
    pub object: String,
    /// What is wrong.
    pub reason: String,
}

const MM: f64 = 1000.0;

impl ObjectInfo {
    /// Information measured from a mesh, with the given symmetries.
    pub fn from_mesh(mesh: &Mesh, symmetries: Vec<Symmetry>) -> Self {
        Self {
            diameter: mesh.diameter(),
            aabb: mesh.aabb(),
            symmetries,
        }
    }

    /// The BOP `models_info.json` entry: millimetres, discrete symmetries as row-major 4x4 matrices (16 numbers),
    /// continuous ones as `{axis, offset}`; symmetry keys are omitted when empty, as BOP does.
    pub fn to_bop_json(&self) -> Value {
        let size = self.aabb.size() * MM;
        let mut entry = json!({
            "diameter": self.diameter * MM,
            "min_x": self.aabb.min.x * MM,
            "min_y": self.aabb.min.y * MM,
            "min_z": self.aabb.min.z * MM,
            "size_x": size.x,
            "size_y": size.y,
            "size_z": size.z,
        });
        let mut discrete = Vec::new();
        let mut continuous = Vec::new();
        for s in &self.symmetries {
            match s {
                Symmetry::Discrete(t) => {
                    let mut m = t.to_homogeneous();
                    for r in 0..3 {
                        m[(r, 3)] *= MM;
                    }
                    discrete.push(Value::from(
                        (0..16).map(|i| m[(i / 4, i % 4)]).collect::<Vec<f64>>(),
                    ));
                }
                Symmetry::Continuous { axis, offset } => continuous.push(json!({
                    "axis": [axis.x, axis.y, axis.z],
                    "offset": [offset.x * MM, offset.y * MM, offset.z * MM],
                })),
            }
        }
        if let Some(obj) = entry.as_object_mut() {
            if !discrete.is_empty() {
                obj.insert("symmetries_discrete".into(), Value::from(discrete));
            }
            if !continuous.is_empty() {
                obj.insert("symmetries_continuous".into(), Value::from(continuous));
            }
        }
        entry
    }

    /// Reads a BOP `models_info.json` entry (millimetres) back into metres. `object` names the entry in errors.
    pub fn from_bop_json(object: &str, entry: &Value) -> Result<Self, ObjectInfoError> {
        let err = |reason: String| ObjectInfoError {
            object: object.to_string(),
            reason,
        };
        let num = |key: &str| -> Result<f64, ObjectInfoError> {
            entry
                .get(key)
                .and_then(Value::as_f64)
                .filter(|v| v.is_finite())
                .ok_or_else(|| err(format!("'{key}' is missing or not a finite number")))
        };
        let diameter = num("diameter")? / MM;
        if diameter <= 0.0 {
            return Err(err(format!("diameter {} mm must be > 0", diameter * MM)));
        }
        let min = Point3::new(num("min_x")?, num("min_y")?, num("min_z")?) / MM;
        let size = Vector3::new(num("size_x")?, num("size_y")?, num("size_z")?) / MM;
        if size.iter().any(|&s| s < 0.0) {
            return Err(err(format!("negative size {size:?}")));
        }
        let floats = |v: &Value, n: usize, what: &str| -> Result<Vec<f64>, ObjectInfoError> {
            let items = v
                .as_array()
                .ok_or_else(|| err(format!("{what} is not a list")))?;
            let out: Vec<f64> = items
                .iter()
                .filter_map(Value::as_f64)
                .filter(|x| x.is_finite())
                .collect();
            if out.len() != n || items.len() != n {
                return Err(err(format!("{what} must hold {n} finite numbers")));
            }
            Ok(out)
        };
        let mut symmetries = Vec::new();
        if let Some(list) = entry.get("symmetries_discrete") {
            let list = list
                .as_array()
                .ok_or_else(|| err("symmetries_discrete is not a list".into()))?;
            for (i, m) in list.iter().enumerate() {
                let v = floats(m, 16, &format!("symmetries_discrete[{i}]"))?;
                let m = Matrix4::from_row_slice(&v);
                let r: Matrix3<f64> = m.fixed_view::<3, 3>(0, 0).into_owned();
                if (r.transpose() * r - Matrix3::identity()).norm() > 1e-3
                    || (r.determinant() - 1.0).abs() > 1e-3
                {
                    return Err(err(format!("symmetries_discrete[{i}] is not a rotation")));
                }
                let rotation = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix(&r));
                let t = Translation3::new(m[(0, 3)], m[(1, 3)], m[(2, 3)]);
                symmetries.push(Symmetry::Discrete(Isometry3::from_parts(
                    Translation3::from(t.vector / MM),
                    rotation,
                )));
            }
        }
        if let Some(list) = entry.get("symmetries_continuous") {
            let list = list
                .as_array()
                .ok_or_else(|| err("symmetries_continuous is not a list".into()))?;
            for (i, s) in list.iter().enumerate() {
                let field = |k: &str| {
                    s.get(k)
                        .ok_or_else(|| err(format!("symmetries_continuous[{i}] has no '{k}'")))
                };
                let a = floats(
                    field("axis")?,
                    3,
                    &format!("symmetries_continuous[{i}].axis"),
                )?;
                let o = floats(
                    field("offset")?,
                    3,
                    &format!("symmetries_continuous[{i}].offset"),
                )?;
                let axis = Unit::try_new(Vector3::new(a[0], a[1], a[2]), 1e-12)
                    .ok_or_else(|| err(format!("symmetries_continuous[{i}].axis is zero")))?;
                symmetries.push(Symmetry::Continuous {
                    axis,
                    offset: Point3::new(o[0], o[1], o[2]) / MM,
                });
            }
        }
        Ok(Self {
            diameter,
            aabb: Aabb {
                min,
                max: min + size,
            },
            symmetries,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn info() -> ObjectInfo {
        ObjectInfo {
            diameter: 0.25,
            aabb: Aabb {
                min: Point3::new(-0.08, -0.03, -0.1),
                max: Point3::new(0.08, 0.03, 0.1),
            },
            symmetries: vec![
                Symmetry::Discrete(Isometry3::from_parts(
                    Translation3::new(0.0, 0.0, 0.01),
                    UnitQuaternion::from_scaled_axis(Vector3::z() * PI),
                )),
                Symmetry::Continuous {
                    axis: Vector3::z_axis(),
                    offset: Point3::new(0.0, 0.0, 0.002),
                },
            ],
        }
    }

    #[test]
    fn bop_json_is_in_millimetres() {
        let j = info().to_bop_json();
        assert!((j["diameter"].as_f64().unwrap() - 250.0).abs() < 1e-9);
        assert!((j["min_x"].as_f64().unwrap() + 80.0).abs() < 1e-9);
        assert!((j["size_z"].as_f64().unwrap() - 200.0).abs() < 1e-9);
        let m = j["symmetries_discrete"][0].as_array().unwrap();
        assert_eq!(m.len(), 16);
        assert!(
            (m[11].as_f64().unwrap() - 10.0).abs() < 1e-9,
            "z translation in mm"
        );
        assert!((m[0].as_f64().unwrap() + 1.0).abs() < 1e-9, "cos(pi)");
        assert!((j["symmetries_continuous"][0]["offset"][2].as_f64().unwrap() - 2.0).abs() < 1e-9);
    }

    #[test]
    fn bop_json_round_trip() {
        let i = info();
        let back = ObjectInfo::from_bop_json("obj_000001", &i.to_bop_json()).unwrap();
        assert!((back.diameter - i.diameter).abs() < 1e-12);
        assert!((back.aabb.max - i.aabb.max).norm() < 1e-12);
        match (&back.symmetries[0], &i.symmetries[0]) {
            (Symmetry::Discrete(a), Symmetry::Discrete(b)) => {
                assert!((a.to_homogeneous() - b.to_homogeneous()).norm() < 1e-9)
            }
            _ => panic!("discrete symmetry lost"),
        }
        assert_eq!(back.symmetries.len(), 2);
    }

    fn symmetry() -> impl proptest::strategy::Strategy<Value = Symmetry> {
        use proptest::prelude::*;
        let vec3 = |r: f64| prop::array::uniform3(-r..r);
        prop_oneof![
            (vec3(0.2), vec3(3.0)).prop_map(|(t, r)| Symmetry::Discrete(Isometry3::new(
                Vector3::from(t),
                Vector3::from(r)
            ))),
            (vec3(1.0), vec3(0.2))
                .prop_filter("an axis needs a direction", |(a, _)| Vector3::from(*a)
                    .norm()
                    > 1e-3)
                .prop_map(|(a, o)| Symmetry::Continuous {
                    axis: Unit::new_normalize(Vector3::from(a)),
                    offset: Point3::from(Vector3::from(o)),
                }),
        ]
    }

    proptest::proptest! {
        /// Every field survives the trip through the BOP shape (millimetres) and back (metres).
        #[test]
        fn any_info_reads_back_from_its_bop_json(
            diameter in 0.001f64..5.0,
            min in proptest::array::uniform3(-1.0f64..1.0),
            size in proptest::array::uniform3(0.0f64..2.0),
            symmetries in proptest::collection::vec(symmetry(), 0..4),
        ) {
            let min = Point3::from(Vector3::from(min));
            let info = ObjectInfo {
                diameter,
                aabb: Aabb { min, max: min + Vector3::from(size) },
                symmetries,
            };
            let back = ObjectInfo::from_bop_json("obj", &info.to_bop_json())
                .map_err(|e| proptest::test_runner::TestCaseError::fail(e.to_string()))?;
            proptest::prop_assert!((back.diameter - info.diameter).abs() < 1e-12);
            proptest::prop_assert!((back.aabb.min - info.aabb.min).norm() < 1e-12);
            proptest::prop_assert!((back.aabb.max - info.aabb.max).norm() < 1e-12);
            // Written discrete ones first, then continuous ones (BOP's two lists).
            let mut expected: Vec<&Symmetry> = info.symmetries.iter().filter(|s| matches!(s, Symmetry::Discrete(_))).collect();
            expected.extend(info.symmetries.iter().filter(|s| matches!(s, Symmetry::Continuous { .. })));
            proptest::prop_assert_eq!(back.symmetries.len(), expected.len());
            for (b, e) in back.symmetries.iter().zip(expected) {
                match (b, e) {
                    (Symmetry::Discrete(b), Symmetry::Discrete(e)) => {
                        proptest::prop_assert!((b.to_homogeneous() - e.to_homogeneous()).norm() < 1e-9);
                    }
                    (Symmetry::Continuous { axis: ba, offset: bo }, Symmetry::Continuous { axis: ea, offset: eo }) => {
                        proptest::prop_assert!((ba.into_inner() - ea.into_inner()).norm() < 1e-9);
                        proptest::prop_assert!((bo - eo).norm() < 1e-12, "offset {} against {}", bo, eo);
                    }
                    _ => proptest::prop_assert!(false, "{:?} read back as {:?}", e, b),
                }
            }
        }

        /// Any JSON value reads as an entry or gives an error naming the object; it never panics.
        #[test]
        fn any_json_reads_or_names_the_object(text in "[\\[\\]{}:,\"a-z_0-9. -]{0,60}") {
            if let Ok(value) = serde_json::from_str::<Value>(&text)
                && let Err(e) = ObjectInfo::from_bop_json("obj_000042", &value)
            {
                proptest::prop_assert!(e.to_string().contains("obj_000042"));
                proptest::prop_assert!(!e.reason.is_empty());
            }
        }
    }

    #[test]
    fn bop_json_errors_name_the_object() {
        let e = ObjectInfo::from_bop_json("obj_000007", &json!({"diameter": 10.0})).unwrap_err();
        assert!(e.to_string().contains("obj_000007") && e.to_string().contains("min_x"));
        let mut j = info().to_bop_json();
        j["symmetries_discrete"] = json!([[1.0, 2.0]]);
        assert!(
            ObjectInfo::from_bop_json("x", &j)
                .unwrap_err()
                .reason
                .contains("16")
        );
    }
}

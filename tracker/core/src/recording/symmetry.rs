//! Symmetry transforms of an object as the BOP toolkit enumerates them (`misc.get_symmetry_transformations`).

use drivers::recording::ModelInfo;
use nalgebra::{
    Isometry3, Matrix3, Point3, Rotation3, Translation3, Unit, UnitQuaternion, Vector3,
};
use scene::mesh::Symmetry;

/// The BOP toolkit's maximum discretisation step of a continuous symmetry, as an arc length in units of the
/// object diameter (`max_sym_disc_step = 0.01` in `eval_calc_errors.py`).
pub const MAX_SYM_DISC_STEP: f64 = 0.01;

/// Why symmetries could not be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("invalid symmetry of object {object}: {reason}")]
pub struct SymmetryError {
    /// Object name.
    pub object: String,
    /// What is wrong.
    pub reason: String,
}

/// Every symmetry transform of an object (object frame, metres), identity first, as BOP combines them: each
/// discrete symmetry (identity included) composed with each discretised continuous rotation
/// (`ceil(pi / MAX_SYM_DISC_STEP)` steps of `2 pi / count` about each axis through its offset, angle 0 included).
pub fn symmetry_transforms(symmetries: &[Symmetry]) -> Vec<Isometry3<f64>> {
    let mut discrete = vec![Isometry3::identity()];
    let mut continuous = Vec::new();
    for s in symmetries {
        match s {
            Symmetry::Discrete(t) => discrete.push(*t),
            Symmetry::Continuous { axis, offset } => {
                let count = (std::f64::consts::PI / MAX_SYM_DISC_STEP).ceil() as usize;
                let step = 2.0 * std::f64::consts::PI / count as f64;
                for i in 0..count {
                    let r = UnitQuaternion::from_axis_angle(axis, i as f64 * step);
                    let t = offset.coords - r * offset.coords;
                    continuous.push(Isometry3::from_parts(Translation3::from(t), r));
                }
            }
        }
    }
    if continuous.is_empty() {
        return discrete;
    }
    let mut out = Vec::with_capacity(discrete.len() * continuous.len());
    for d in &discrete {
        for c in &continuous {
            out.push(c * d);
        }
    }
    out
}

/// The symmetries declared in a recording's `models_info.json` entry, validated (orthonormal rotations, unit
/// axes after normalisation, finite numbers).
pub fn symmetries_of(model: &ModelInfo) -> Result<Vec<Symmetry>, SymmetryError> {
    let err = |reason: String| SymmetryError {
        object: model.name.clone(),
        reason,
    };
    let mut out = Vec::new();
    for (k, m) in model.symmetries_discrete.iter().enumerate() {
        if m.iter().any(|v| !v.is_finite()) {
            return Err(err(format!(
                "symmetries_discrete[{k}] has a non-finite entry"
            )));
        }
        let r = Matrix3::new(m[0], m[1], m[2], m[4], m[5], m[6], m[8], m[9], m[10]);
        if (r.transpose() * r - Matrix3::identity()).abs().max() > 1e-4 || r.determinant() < 0.0 {
            return Err(err(format!("symmetries_discrete[{k}] is not a rotation")));
        }
        let rot = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r));
        let t = Translation3::new(m[3], m[7], m[11]);
        out.push(Symmetry::Discrete(Isometry3::from_parts(t, rot)));
    }
    for (k, c) in model.symmetries_continuous.iter().enumerate() {
        let axis = Vector3::from(c.axis);
        if !axis.iter().all(|v| v.is_finite()) || axis.norm() < 1e-9 {
            return Err(err(format!(
                "symmetries_continuous[{k}] axis is zero or not finite"
            )));
        }
        if c.offset_m.iter().any(|v| !v.is_finite()) {
            return Err(err(format!(
                "symmetries_continuous[{k}] offset is not finite"
            )));
        }
        out.push(Symmetry::Continuous {
            axis: Unit::new_normalize(axis),
            offset: Point3::from(c.offset_m),
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_symmetry_is_identity_only() {
        let t = symmetry_transforms(&[]);
        assert_eq!(t, vec![Isometry3::identity()]);
    }

    #[test]
    fn continuous_axis_has_315_steps_including_identity() {
        let s = Symmetry::Continuous {
            axis: Vector3::z_axis(),
            offset: Point3::new(0.1, 0.0, 0.0),
        };
        let t = symmetry_transforms(&[s]);
        // ceil(pi / 0.01) = 315
        assert_eq!(t.len(), 315);
        assert!(
            (t[0].to_homogeneous() - Isometry3::identity().to_homogeneous())
                .abs()
                .max()
                < 1e-12
        );
        // Every transform keeps the axis point fixed, and the k-th turns a point off the axis by k steps of
        // 2 pi / 315 about it.
        for (k, x) in t.iter().enumerate() {
            assert!((x * Point3::new(0.1, 0.0, 0.3) - Point3::new(0.1, 0.0, 0.3)).norm() < 1e-12);
            let off = x * Point3::new(0.2, 0.0, 0.3) - Point3::new(0.1, 0.0, 0.3);
            assert!((off.norm() - 0.1).abs() < 1e-12 && off.z.abs() < 1e-12);
            let angle = off.y.atan2(off.x).rem_euclid(std::f64::consts::TAU);
            let expected =
                (k as f64 * std::f64::consts::TAU / 315.0).rem_euclid(std::f64::consts::TAU);
            let diff = (angle - expected).abs();
            assert!(
                diff.min(std::f64::consts::TAU - diff) < 1e-9,
                "step {k}: {angle} rad"
            );
        }
    }

    #[test]
    fn discrete_times_continuous() {
        let flip = Isometry3::rotation(Vector3::x() * std::f64::consts::PI);
        let s = [
            Symmetry::Discrete(flip),
            Symmetry::Continuous {
                axis: Vector3::z_axis(),
                offset: Point3::origin(),
            },
        ];
        assert_eq!(symmetry_transforms(&s).len(), 2 * 315);
    }

    #[test]
    fn model_info_with_bad_rotation_is_refused() {
        let mut m = ModelInfo {
            name: "box".into(),
            diameter_m: 0.1,
            min_m: [0.0; 3],
            size_m: [0.1; 3],
            symmetries_discrete: vec![[
                2.0, 0., 0., 0., 0., 1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1.,
            ]],
            symmetries_continuous: vec![],
        };
        let e = symmetries_of(&m).unwrap_err();
        assert!(e.to_string().contains("box") && e.to_string().contains("not a rotation"));
        m.symmetries_discrete = vec![[
            -1., 0., 0., 0., 0., -1., 0., 0.01, 0., 0., 1., 0., 0., 0., 0., 1.,
        ]];
        let s = symmetries_of(&m).unwrap();
        match s[0] {
            Symmetry::Discrete(t) => assert!((t.translation.vector.y - 0.01).abs() < 1e-12),
            _ => panic!("expected a discrete symmetry"),
        }
    }
}

//! SE(3) helpers on `nalgebra` (f64 state) and conversion to `glam` (f32) for the renderer.
//!
//! Twists are `[v; w]`: translational part first (metres), rotational part second (radians, axis-angle), matching the
//! usual left-multiplied perturbation `T' = exp(xi) * T`.

use nalgebra::{Isometry3, Matrix3, Translation3, UnitQuaternion, Vector3, Vector6};

/// Skew-symmetric (cross-product) matrix of `w`: `hat(w) * x == w.cross(&x)`.
pub fn hat(w: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -w.z, w.y, w.z, 0.0, -w.x, -w.y, w.x, 0.0)
}

/// The left Jacobian `V` of SO(3) used by the SE(3) exponential: `t = V(w) * v`.
fn left_jacobian(w: &Vector3<f64>) -> Matrix3<f64> {
    let theta2 = w.norm_squared();
    let theta = theta2.sqrt();
    let k = hat(w);
    let (a, b) = if theta < 1e-6 {
        // Taylor expansions of (1 - cos)/theta^2 and (theta - sin)/theta^3.
        (0.5 - theta2 / 24.0, 1.0 / 6.0 - theta2 / 120.0)
    } else {
        (
            (1.0 - theta.cos()) / theta2,
            (theta - theta.sin()) / (theta2 * theta),
        )
    };
    Matrix3::identity() + k * a + k * k * b
}

/// Exponential map from a twist `[v; w]` (metres, radians) to a rigid transform.
pub fn exp_se3(xi: &Vector6<f64>) -> Isometry3<f64> {
    let v = xi.fixed_rows::<3>(0).into_owned();
    let w = xi.fixed_rows::<3>(3).into_owned();
    let rotation = UnitQuaternion::from_scaled_axis(w);
    let t = left_jacobian(&w) * v;
    Isometry3::from_parts(Translation3::from(t), rotation)
}

/// Logarithm map: the twist `[v; w]` whose exponential is `t` (rotation angle in `[0, pi]`).
pub fn log_se3(t: &Isometry3<f64>) -> Vector6<f64> {
    let w = t.rotation.scaled_axis();
    let v = left_jacobian(&w)
        .try_inverse()
        .map(|inv| inv * t.translation.vector)
        // V is invertible for angles below 2*pi; scaled_axis never exceeds pi, so this is only a guard.
        .unwrap_or(t.translation.vector);
    Vector6::new(v.x, v.y, v.z, w.x, w.y, w.z)
}

/// Rotation angle of `a^-1 * b`, radians in `[0, pi]`.
pub fn rotation_distance(a: &Isometry3<f64>, b: &Isometry3<f64>) -> f64 {
    a.rotation.angle_to(&b.rotation)
}

/// Distance between the translations of `a` and `b`, metres.
pub fn translation_distance(a: &Isometry3<f64>, b: &Isometry3<f64>) -> f64 {
    (a.translation.vector - b.translation.vector).norm()
}

/// Interpolates between `a` (`s = 0`) and `b` (`s = 1`) along the SE(3) geodesic `a * exp(s * log(a^-1 b))`.
pub fn interpolate(a: &Isometry3<f64>, b: &Isometry3<f64>, s: f64) -> Isometry3<f64> {
    let delta = log_se3(&(a.inverse() * b));
    a * exp_se3(&(delta * s))
}

/// The pose as an f32 `glam` affine transform (rotation then translation), for rasterisers and GPU uploads.
pub fn to_glam_affine(t: &Isometry3<f64>) -> glam::Affine3A {
    let m = t.rotation.to_rotation_matrix();
    let m = m.matrix();
    let col = |c: usize| glam::Vec3::new(m[(0, c)] as f32, m[(1, c)] as f32, m[(2, c)] as f32);
    let tr = &t.translation.vector;
    glam::Affine3A::from_mat3_translation(
        glam::Mat3::from_cols(col(0), col(1), col(2)),
        glam::Vec3::new(tr.x as f32, tr.y as f32, tr.z as f32),
    )
}

/// A pose from a rotation about a unit axis (radians) and a translation (metres).
pub fn pose_from_axis_angle(
    axis: &Vector3<f64>,
    angle_rad: f64,
    translation: &Vector3<f64>,
) -> Isometry3<f64> {
    let scaled = if axis.norm() > 0.0 {
        axis.normalize() * angle_rad
    } else {
        Vector3::zeros()
    };
    Isometry3::from_parts(
        Translation3::from(*translation),
        UnitQuaternion::from_scaled_axis(scaled),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn exp_log_round_trip(
            v in proptest::array::uniform3(-2.0f64..2.0),
            w in proptest::array::uniform3(-1.7f64..1.7),
        ) {
            let xi = Vector6::new(v[0], v[1], v[2], w[0], w[1], w[2]);
            prop_assume!(Vector3::new(w[0], w[1], w[2]).norm() < 3.0);
            let t = exp_se3(&xi);
            let back = log_se3(&t);
            prop_assert!((back - xi).norm() < 1e-9, "{xi:?} -> {back:?}");
        }

        #[test]
        fn interpolation_hits_endpoints(
            v in proptest::array::uniform3(-1.0f64..1.0),
            w in proptest::array::uniform3(-1.0f64..1.0),
        ) {
            let a = exp_se3(&Vector6::new(0.1, 0.2, 0.5, 0.3, -0.2, 0.1));
            let b = a * exp_se3(&Vector6::new(v[0], v[1], v[2], w[0], w[1], w[2]));
            let s0 = interpolate(&a, &b, 0.0);
            let s1 = interpolate(&a, &b, 1.0);
            prop_assert!(translation_distance(&s0, &a) < 1e-9 && rotation_distance(&s0, &a) < 1e-9);
            prop_assert!(translation_distance(&s1, &b) < 1e-9 && rotation_distance(&s1, &b) < 1e-9);
        }
    }

    #[test]
    fn exp_of_pure_rotation_and_translation() {
        let t = exp_se3(&Vector6::new(1.0, 2.0, 3.0, 0.0, 0.0, 0.0));
        assert!((t.translation.vector - Vector3::new(1.0, 2.0, 3.0)).norm() < 1e-12);
        let r = exp_se3(&Vector6::new(
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
            std::f64::consts::FRAC_PI_2,
        ));
        let x = r * nalgebra::Point3::new(1.0, 0.0, 0.0);
        assert!((x - nalgebra::Point3::new(0.0, 1.0, 0.0)).norm() < 1e-12);
    }

    #[test]
    fn glam_affine_matches_nalgebra() {
        let t = exp_se3(&Vector6::new(0.1, -0.2, 0.7, 0.4, 0.5, -0.6));
        let g = to_glam_affine(&t);
        let p = nalgebra::Point3::new(0.03, -0.02, 0.05);
        let q = t * p;
        let qg = g.transform_point3(glam::Vec3::new(0.03, -0.02, 0.05));
        assert!(
            (q.x as f32 - qg.x).abs() < 1e-6
                && (q.y as f32 - qg.y).abs() < 1e-6
                && (q.z as f32 - qg.z).abs() < 1e-6
        );
    }
}

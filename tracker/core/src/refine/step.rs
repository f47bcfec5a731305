//! One bounded Levenberg-Marquardt step: solving the normal equations, bounding the step the way the paper's
//! refiner is bounded, and applying it about the object's centre.

use super::normal_equations::NormalEquations;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3, Vector6};

/// Bounds of one refinement step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepBounds {
    /// Largest rotation per step, radians.
    pub max_rotation: f64,
    /// Largest translation per step, metres.
    pub max_translation: f64,
}

/// Solves `(H + damping) xi = -g` with Levenberg-Marquardt damping `lambda` (relative to the diagonal, plus a tiny
/// absolute floor so unobservable directions, e.g. about a symmetry axis, stay put) and clamps the step.
pub fn solve_step(ne: &NormalEquations, lambda: f64, bounds: &StepBounds) -> Option<Vector6<f64>> {
    if ne.count < 6 {
        return None;
    }
    let mut a = ne.hessian();
    let scale = (0..6).map(|i| a[(i, i)]).fold(0.0f64, f64::max).max(1e-12);
    for i in 0..6 {
        a[(i, i)] += lambda * a[(i, i)] + 1e-6 * scale;
    }
    let xi = a.cholesky()?.solve(&(-ne.g));
    if !xi.iter().all(|v| v.is_finite()) {
        return None;
    }
    Some(clamp_step(xi, bounds))
}

/// Scales `xi` down so its rotation and translation parts respect `bounds`.
pub fn clamp_step(xi: Vector6<f64>, bounds: &StepBounds) -> Vector6<f64> {
    let t = xi.fixed_rows::<3>(0).norm();
    let r = xi.fixed_rows::<3>(3).norm();
    let s = (bounds.max_translation / t.max(1e-12))
        .min(bounds.max_rotation / r.max(1e-12))
        .min(1.0);
    xi * s
}

/// Applies increment `xi` about the object centre `center_obj` (object frame) to `pose` (`T_cam_obj`).
pub fn apply_step(
    pose: &Isometry3<f64>,
    center_obj: &Vector3<f64>,
    xi: &Vector6<f64>,
) -> Isometry3<f64> {
    let c = pose * nalgebra::Point3::from(*center_obj);
    let dr = UnitQuaternion::from_scaled_axis(Vector3::new(xi[3], xi[4], xi[5]));
    let v = Vector3::new(xi[0], xi[1], xi[2]);
    // New pose: centre moves by v, orientation turns by dr about the centre.
    let rotation = dr * pose.rotation;
    let new_center = c.coords + v;
    let translation = new_center - rotation * center_obj;
    Isometry3::from_parts(Translation3::from(translation), rotation)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn step_rotates_about_the_centre_and_translates_it() {
        let pose = Isometry3::translation(0.1, 0.0, 1.0);
        let center = Vector3::new(0.0, 0.0, 0.05);
        let xi = Vector6::new(0.01, 0.0, 0.0, 0.0, 0.3, 0.0);
        let new = apply_step(&pose, &center, &xi);
        let c0 = pose * nalgebra::Point3::from(center);
        let c1 = new * nalgebra::Point3::from(center);
        assert!((c1 - c0 - Vector3::new(0.01, 0.0, 0.0)).norm() < 1e-12);
        assert!((new.rotation.angle() - 0.3).abs() < 1e-12);
    }

    #[test]
    fn steps_are_bounded() {
        let b = StepBounds {
            max_rotation: 20f64.to_radians(),
            max_translation: 0.05,
        };
        let xi = clamp_step(Vector6::new(1.0, 0.0, 0.0, 0.0, 0.0, 0.1), &b);
        assert!((xi.fixed_rows::<3>(0).norm() - 0.05).abs() < 1e-12);
        let xi = clamp_step(Vector6::new(0.0, 0.0, 0.0, 0.0, 2.0, 0.0), &b);
        assert!((xi.fixed_rows::<3>(3).norm() - 20f64.to_radians()).abs() < 1e-12);
        let small = Vector6::new(0.001, 0.0, 0.0, 0.0, 0.01, 0.0);
        assert_eq!(clamp_step(small, &b), small);
    }

    #[test]
    fn gauss_newton_recovers_a_translation_from_point_to_plane_residuals() {
        // Three orthogonal planes through the true centre: residuals n . (p_true - p).
        let truth = Vector3::new(0.01, -0.02, 0.005);
        let mut ne = NormalEquations::default();
        let normals = [Vector3::x(), Vector3::y(), Vector3::z()];
        for n in &normals {
            for corner in 0..8 {
                let sign = |bit: u32| {
                    if corner & (1 << bit) != 0 {
                        0.02
                    } else {
                        -0.02
                    }
                };
                let p = Vector3::new(sign(0), sign(1), sign(2));
                // r = n . (q - p') with q = p + truth: gradient wrt p' is -n.
                let r = n.dot(&truth);
                ne.add_point(&(-n), &p, r, 1.0);
            }
        }
        let b = StepBounds {
            max_rotation: 1.0,
            max_translation: 1.0,
        };
        let xi = solve_step(&ne, 0.0, &b).unwrap();
        assert!((xi.fixed_rows::<3>(0) - truth).norm() < 1e-6, "{xi}");
    }
}

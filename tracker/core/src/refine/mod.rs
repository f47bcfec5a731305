//! Render-and-compare pose refinement (paper section 3.2, as Gauss-Newton / Levenberg-Marquardt): residual terms
//! ("modalities") accumulate into 6x6 normal equations over a pose increment; the solver bounds every step the way
//! the paper's refiner is bounded (about 20 degrees and half a diameter).
//!
//! The increment is parametrised about the object's centre `c` (camera frame): `xi = [v; w]` moves a point `P` of
//! the object to `R(w) (P - c) + c + v`. A residual `r(P)` with gradient `g = dr/dP` then has the Jacobian
//! `[g; (P - c) x g]`.

mod depth_term;
mod event_term;
mod intensity_term;
mod model_view;

pub use depth_term::{DepthTerm, DepthTermStats};
pub use event_term::{BinnedWindow, EventEdges, EventTerm, EventTermKind, EventTermStats};
pub use intensity_term::{IntensityEdges, IntensityTerm};
pub use model_view::{ContourPoint, ModelView, SurfacePoint};

use nalgebra::{Isometry3, Matrix6, Translation3, UnitQuaternion, Vector3, Vector6};
use scene::geometry::PinholeCamera;

/// Accumulated weighted least-squares normal equations `H xi = -g` of one iteration.
///
/// `H` is symmetric, so only its upper triangle (row <= column) is accumulated; [`Self::hessian`] gives the whole
/// matrix.
#[derive(Debug, Clone, Copy)]
pub struct NormalEquations {
    /// Upper triangle (row <= column) of `sum w J J^T`; the entries below the diagonal stay zero.
    pub h: Matrix6<f64>,
    /// `sum w J r`.
    pub g: Vector6<f64>,
    /// `sum w r^2`.
    pub cost: f64,
    /// Residuals accumulated.
    pub count: usize,
}

impl Default for NormalEquations {
    fn default() -> Self {
        Self {
            h: Matrix6::zeros(),
            g: Vector6::zeros(),
            cost: 0.0,
            count: 0,
        }
    }
}

impl NormalEquations {
    /// Adds residual `r` with weight `w`, gradient `grad = dr/dP` at object point `p` about centre `c`.
    #[inline(always)]
    pub fn add_point(&mut self, grad: &Vector3<f64>, p_minus_c: &Vector3<f64>, r: f64, w: f64) {
        let rot = p_minus_c.cross(grad);
        let j = [grad.x, grad.y, grad.z, rot.x, rot.y, rot.z];
        let wj = j.map(|x| w * x);
        for (c, jc) in j.into_iter().enumerate() {
            for (r, wjr) in wj.into_iter().enumerate().take(c + 1) {
                self.h[(r, c)] += wjr * jc;
            }
        }
        let wr = w * r;
        for (g, jr) in self.g.iter_mut().zip(j) {
            *g += wr * jr;
        }
        self.cost += w * r * r;
        self.count += 1;
    }

    /// The whole symmetric `sum w J J^T`: the accumulated upper triangle mirrored below the diagonal.
    pub fn hessian(&self) -> Matrix6<f64> {
        let mut h = self.h;
        for c in 0..6 {
            for r in c + 1..6 {
                h[(r, c)] = h[(c, r)];
            }
        }
        h
    }

    /// Adds another set of equations scaled by `weight`.
    pub fn add_scaled(&mut self, other: &NormalEquations, weight: f64) {
        self.h += other.h * weight;
        self.g += other.g * weight;
        self.cost += other.cost * weight;
        self.count += other.count;
    }
}

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

/// Robust contour-to-edge residuals of one accumulation: the offset of an observed outline point from the
/// projected contour point along its image normal (full-image pixels), Cauchy-weighted with scale `3 sigma_px`.
pub(crate) struct ContourResiduals<'a> {
    /// The full event camera.
    pub camera: &'a PinholeCamera,
    /// The object's centre at the pose being refined, camera frame (the increment's pivot).
    pub center: nalgebra::Point3<f64>,
    /// Residual scale, full-image pixels.
    pub sigma_px: f64,
    /// Residuals beyond this (full-image pixels) are skipped.
    pub max_px: f64,
}

impl ContourResiduals<'_> {
    /// Adds the residual of contour point `p` (camera frame, image normal `normal`) against observed outline
    /// point `e`, less `shift` pixels, with weight `weight / sigma^2` before the robust factor. Returns whether it
    /// was added (not behind the camera, not beyond `max_px`).
    pub fn add(
        &self,
        ne: &mut NormalEquations,
        p: &nalgebra::Point3<f64>,
        normal: [f64; 2],
        e: &[f64; 2],
        shift: f64,
        weight: f64,
    ) -> bool {
        let Some((offset, grad)) = normal_offset(self.camera, p, normal, e) else {
            return false;
        };
        let r = offset - shift;
        if r.abs() > self.max_px {
            return false;
        }
        let robust = 1.0 / (1.0 + (r / (3.0 * self.sigma_px)).powi(2));
        ne.add_point(
            &grad,
            &(p - self.center),
            r,
            weight * robust / (self.sigma_px * self.sigma_px),
        );
        true
    }
}

/// Offset of image point `e` from the projection of camera-frame point `p` along the unit image normal `m`
/// (full-image pixels, positive outwards), and its gradient with respect to `p` (`-m^T d pi / d P`); `None`
/// behind the camera.
#[inline]
pub(crate) fn normal_offset(
    camera: &PinholeCamera,
    p: &nalgebra::Point3<f64>,
    m: [f64; 2],
    e: &[f64; 2],
) -> Option<(f64, Vector3<f64>)> {
    if p.z <= 0.01 {
        return None;
    }
    let iz = 1.0 / p.z;
    let u = camera.fx * p.x * iz + camera.cx;
    let v = camera.fy * p.y * iz + camera.cy;
    let [mx, my] = m;
    let grad = -Vector3::new(
        mx * camera.fx * iz,
        my * camera.fy * iz,
        -(mx * camera.fx * p.x + my * camera.fy * p.y) * iz * iz,
    );
    Some((mx * (e[0] - u) + my * (e[1] - v), grad))
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

    proptest::proptest! {
        #[test]
        fn hessian_is_the_whole_weighted_sum_of_jacobian_products(
            points in proptest::collection::vec(
                (proptest::array::uniform3(-1.0f64..1.0), proptest::array::uniform3(-0.2f64..0.2), 0.01f64..10.0),
                1..40,
            ),
        ) {
            let mut ne = NormalEquations::default();
            let mut full = Matrix6::zeros();
            for (grad, arm, w) in &points {
                let grad = Vector3::from(*grad);
                let arm = Vector3::from(*arm);
                ne.add_point(&grad, &arm, 0.5, *w);
                let rot = arm.cross(&grad);
                let j = Vector6::new(grad.x, grad.y, grad.z, rot.x, rot.y, rot.z);
                full += j * j.transpose() * *w;
            }
            let h = ne.hessian();
            proptest::prop_assert_eq!(h, h.transpose());
            proptest::prop_assert!((h - full).abs().max() <= 1e-12 * full.abs().max().max(1.0));
            proptest::prop_assert_eq!(ne.count, points.len());
        }
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

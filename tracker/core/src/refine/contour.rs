//! Contour-to-edge residuals shared by the event and intensity terms: the offset of an observed outline point
//! from the projected contour along its image normal, and its gradient.

use super::normal_equations::NormalEquations;
use nalgebra::Vector3;
use scene::geometry::PinholeCamera;

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

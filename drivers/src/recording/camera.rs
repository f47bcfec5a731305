//! `camera.json`: both cameras' intrinsics, distortion, resolution, and the depth-to-event extrinsic.

use serde::{Deserialize, Serialize};

/// A pinhole camera with OpenCV distortion, in pixels. Unknown keys are refused, like the rig's.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraIntrinsics {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Focal length along x, pixels.
    pub fx: f64,
    /// Focal length along y, pixels.
    pub fy: f64,
    /// Principal point x, pixels.
    pub cx: f64,
    /// Principal point y, pixels.
    pub cy: f64,
    /// OpenCV distortion coefficients `k1, k2, p1, p2, k3` (empty or all zero: none).
    #[serde(default)]
    pub distortion: Vec<f64>,
}

impl CameraIntrinsics {
    /// Checks sizes, focal lengths and coefficients; returns what is wrong, naming the field.
    pub fn validate(&self, name: &str) -> Result<(), String> {
        if self.width == 0 || self.height == 0 || self.width > 16384 || self.height > 16384 {
            return Err(format!(
                "{name}: resolution {}x{} is not in 1..16384",
                self.width, self.height
            ));
        }
        for (field, v) in [("fx", self.fx), ("fy", self.fy)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!(
                    "{name}.{field} = {v} must be a positive number of pixels"
                ));
            }
        }
        for (field, v) in [("cx", self.cx), ("cy", self.cy)] {
            if !v.is_finite() {
                return Err(format!("{name}.{field} = {v} is not finite"));
            }
        }
        if self.distortion.len() > 8 || self.distortion.iter().any(|d| !d.is_finite()) {
            return Err(format!(
                "{name}.distortion must be at most 8 finite numbers (k1, k2, p1, p2, k3, ...)"
            ));
        }
        Ok(())
    }
}

/// The sensor rig: event camera (the master frame), depth camera, and `T_event_depth`. Unknown keys are
/// refused: a misspelt `depth_scale_m` would otherwise fall back to millimetres without a word.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraRig {
    /// The event camera (EVK4: 1280x720).
    pub event_camera: CameraIntrinsics,
    /// The depth camera (D435i: 848x480 at 30 Hz).
    pub depth_camera: CameraIntrinsics,
    /// Row-major 4x4 rigid transform taking points in the depth camera frame (metres, OpenCV axes) into the
    /// event camera frame.
    #[serde(rename = "T_event_depth")]
    pub t_event_depth: [[f64; 4]; 4],
    /// Metres per unit of the stored depth images (0.001: millimetres).
    #[serde(default = "default_depth_scale")]
    pub depth_scale_m: f64,
}

fn default_depth_scale() -> f64 {
    0.001
}

impl CameraRig {
    /// Checks both cameras and that `T_event_depth` is a rigid transform.
    pub fn validate(&self) -> Result<(), String> {
        self.event_camera.validate("event_camera")?;
        self.depth_camera.validate("depth_camera")?;
        if !(self.depth_scale_m.is_finite() && self.depth_scale_m > 0.0) {
            return Err(format!(
                "depth_scale_m = {} must be positive",
                self.depth_scale_m
            ));
        }
        let m = &self.t_event_depth;
        if m.iter().flatten().any(|v| !v.is_finite()) {
            return Err("T_event_depth has non-finite entries".into());
        }
        if m[3] != [0.0, 0.0, 0.0, 1.0] {
            return Err(format!(
                "T_event_depth last row is {:?}, expected [0, 0, 0, 1]",
                m[3]
            ));
        }
        for i in 0..3 {
            for j in 0..3 {
                let dot: f64 = (0..3).map(|k| m[k][i] * m[k][j]).sum();
                let want = if i == j { 1.0 } else { 0.0 };
                if (dot - want).abs() > 1e-6 {
                    return Err("T_event_depth rotation part is not orthonormal".into());
                }
            }
        }
        let det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
        if det < 0.0 {
            return Err("T_event_depth rotation part is a reflection (determinant -1)".into());
        }
        Ok(())
    }
}

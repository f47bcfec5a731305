//! Geometry: camera models, regions of interest and SE(3) helpers.
//!
//! Conventions (DESIGN section 3): metres and radians; OpenCV camera frame (x right, y down, z forward); poses are
//! `T_cam_obj: nalgebra::Isometry3<f64>` mapping object-frame points into the camera frame.

mod camera;
pub mod se3;

pub use camera::{CameraError, PinholeCamera, Roi};

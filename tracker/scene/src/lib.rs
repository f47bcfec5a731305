//! EventTrack6D's scene: what an object and a camera are, and how a posed object looks to a camera.
//!
//! - [`geometry`]: pinhole cameras, regions of interest, SE(3) helpers (metres, radians, OpenCV camera frame,
//!   poses `T_cam_obj`).
//! - [`mesh`]: OBJ meshes with textures, measurements, surface sampling, symmetries, render meshes simplified
//!   within a tolerance.
//! - [`render`]: the [`render::Renderer`] interface with the deterministic CPU rasteriser and, behind the `gpu`
//!   feature, the wgpu/Vulkan renderer.
//!
//! Depends on no other crate of the workspace: the tracker, the evaluation and the simulator (`hil-sim`) build on
//! it; it knows nothing of events, depth sensors, tracking or transports.

pub mod geometry;
pub mod mesh;
pub mod render;

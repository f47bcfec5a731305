//! EventTrack6D's algorithm (crate `eventtrack6d-core`, `tracker` in code): from events, depth frames and a CAD
//! mesh to a pose per object per tick.
//!
//! - [`recon`]: the dual-modal reconstruction (paper 3.1): intensity `I_t` from events, depth `D_t` carried from
//!   the last depth frame.
//! - [`refine`]: render-and-compare refinement (paper 3.2): residual terms over 6x6 normal equations, the bounded
//!   Levenberg-Marquardt step.
//! - [`track`]: the per-tick tracker ([`track::PoseTracker`], [`track::EventTrack6d`]), its configuration, quality
//!   and state, re-detection, and the offline driver over a recording.
//! - [`recording`]: what the tracker reads from a recording or rig description (rig, objects, ticks, ground
//!   truth) and its pose CSV.
//!
//! Depends on `drivers` (event formats, recordings, the trigger timeline) and `scene` (geometry, meshes,
//! renderers) only: no async runtime, no network, no CAN. Evaluation (`eval`) and the application
//! (`eventtrack6d`) build on it.

pub mod recon;
pub mod recording;
pub mod refine;
pub mod track;

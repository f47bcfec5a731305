//! EventTrack6D tracker library.

pub mod eval;
pub mod geometry;
pub mod mesh;
pub mod publish;
pub mod recon;
pub mod refine;
pub mod render;
pub mod runtime;
pub mod track;

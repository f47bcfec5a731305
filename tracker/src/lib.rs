//! EventTrack6D tracker library.

pub mod eval;
pub mod geometry;
pub mod mesh;
pub mod render;
pub mod track;
pub mod publish;
pub mod runtime;

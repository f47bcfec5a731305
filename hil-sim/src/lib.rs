//! Hardware-in-the-loop simulator for EventTrack6D.
pub mod pattern;

pub mod objects;

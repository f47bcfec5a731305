//! Hardware-in-the-loop simulator for EventTrack6D.

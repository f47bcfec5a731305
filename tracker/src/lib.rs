//! EventTrack6D tracker library.

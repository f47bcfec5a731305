//! Sensor I/O for EventTrack6D.
//!
//! Event-camera stream formats (EVT 3.0, EVT 2.0, EVT 2.1) with streaming decoders and encoders, `.raw`
//! files, the recording directory format, and the trigger timeline that places depth frames and pose
//! ticks on the event camera's clock. Depends on nothing else in the workspace.

pub mod anomaly;
pub mod event;
pub mod evk4;
pub mod formats;
pub mod raw;
pub mod recording;
pub mod summary;
pub mod timeline;
pub mod transfer_ring;

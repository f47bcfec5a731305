//! Hardware-in-the-loop simulator for EventTrack6D: synthetic scenes with the procedural object library,
//! motion after the paper's test sequences, ESIM event simulation driven by the renderer, a RealSense-like
//! depth sensor, and recordings in the format of `docs/recording-format.md`; and the emulated devices that play
//! recordings to the tracker as hardware would (`usb_camera`, `ros2_play`).

pub mod depth_sensor;
pub mod esim;
pub mod generate;
pub mod motion;
pub mod objects;
pub mod pattern;
pub mod preview;
pub mod rig;
pub mod rng;
pub mod ros2_play;
pub mod suite;
pub mod usb_camera;

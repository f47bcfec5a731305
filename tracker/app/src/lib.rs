//! EventTrack6D's application: the real-time process around the tracker and the transports its poses leave on.
//!
//! - [`runtime`]: sources (replay, demo) -> trigger timeline -> tracker thread -> sinks, with health, status and
//!   latency.
//! - [`publish`]: the sinks: zenoh / ROS 2, CAN (SocketCAN, candump log), CSV.
//!
//! The `eventtrack6d` binary (`src/bin/eventtrack6d`) is the command line over this crate, the tracker (`tracker`)
//! and the evaluation (`eval`). Nothing in the workspace depends on this crate but the workspace tests.

pub mod publish;
pub mod runtime;

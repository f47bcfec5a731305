//! Shared helpers for the workspace-level end-to-end tests.

#![allow(clippy::unwrap_used, clippy::expect_used)]
/// The CPU time of the whole process, for the benchmarks that count every thread.
pub mod cpu_time;
pub mod dbc;
/// A renderer that runs a hook before every render (counting renders, noting threads).
pub mod render_hook;
/// How a streamed run's counters may differ from the offline driver's.
pub mod replay_counters;
/// The independent ROS 2 type system (rosbags, `tests/ros2/rosbags_check.py`).
pub mod rosbags;
/// The tracker parameter files of `config/tracker/`.
pub mod shipped_params;
/// A tracker in steady state on a generated recording (tick benchmark, no-allocation test).
pub mod tick_fixture;
/// The test VM with the kernel's USB/IP host side (`tests/vm/`).
pub mod vm;
/// A real-time run held until a test's zenoh session is connected, and that session.
pub mod zenoh_run;

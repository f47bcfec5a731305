//! Trigger MCU firmware for EventTrack6D: the rig's time base (DESIGN sections 4 and 8).
//!
//! The MCU emits a depth-camera pulse train (30 Hz by default) from a 32-bit master timer and
//! an event-camera train at exactly 4 x that rate from a 16-bit slave timer started through the
//! internal trigger, so the two stay phase-locked. The event pulse that coincides with a depth
//! pulse is wider (the phase code), so the event stream alone carries the full timeline.
//!
//! This library is the `no_std` schedule core, host-tested:
//! - [`plan`]: prescaler / reload / compare values for a timer clock, or a refusal when the
//!   rates or the exact 4:1 ratio cannot be met;
//! - [`train`]: start, stop, pulse counting, the width to preload for each event pulse;
//! - [`edges`]: the ideal edge sequence of a run, in timer ticks;
//! - [`command`]: the UART command interface (`start`, `stop`, `status`, `rate`).
//!
//! The binaries (`trigger-board` for the Nucleo-F401RE, `trigger-qemu` for QEMU's mps2-an386)
//! are cross-built with the `board` / `qemu` features; see `docs/firmware-trigger.md`.
#![no_std]
#![warn(missing_docs)]

pub mod command;
pub mod edges;
pub mod plan;
pub mod train;

pub use edges::{Edge, EdgeSchedule, rescale};
pub use plan::{EVENT_PER_DEPTH, Line, PlanError, PulseWidths, TimerPlan};
pub use train::{PulseCounts, PulseTrain, TrainError};

/// Timer clock of the STM32F401's APB1 timers (TIM2..TIM5) on the board, Hz: SYSCLK 84 MHz
/// from the PLL, APB1 at 42 MHz, timers at 2 x APB1.
pub const BOARD_TIMER_CLOCK_HZ: u32 = 84_000_000;

/// Default depth-camera rate, Hz (the D435i runs at 30 fps in slave mode).
pub const DEFAULT_DEPTH_HZ: u32 = 30;

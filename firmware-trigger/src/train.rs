//! Run state of the pulse generator: start, stop, pulse counting and the width to preload for
//! the next event pulse.
//!
//! The board drives this from the slave timer's update interrupt: with compare preload enabled,
//! a compare value written during pulse `k` takes effect at the update that starts pulse `k + 1`.
//! Before start the board parks both counters at their reload value (outputs low) and preloads
//! the width [`PulseTrain::start`] returns for pulse 0; the first update (the first counter tick)
//! then starts pulse 0, and every update's interrupt, pulse 0's included, calls
//! [`PulseTrain::on_event_pulse`] and preloads the width it returns for the following pulse.

use core::fmt;

use crate::plan::{EVENT_PER_DEPTH, TimerPlan};

/// Why a run-state change was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TrainError {
    /// `start` while already running.
    AlreadyRunning,
    /// `stop` while not running.
    NotRunning,
    /// A new plan was offered while running (stop first: changing rates mid-run breaks lock).
    Running,
}

impl fmt::Display for TrainError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            TrainError::AlreadyRunning => "already running",
            TrainError::NotRunning => "not running",
            TrainError::Running => "running: stop first",
        })
    }
}

/// Pulse counts of a run (the current one, or the last one after a stop).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PulseCounts {
    /// Event (120 Hz) pulses begun since start.
    pub event: u64,
    /// Depth (30 Hz) pulses begun since start: one per `EVENT_PER_DEPTH` event pulses, the
    /// first together with event pulse 0.
    pub depth: u64,
}

/// The generator's run state over a [`TimerPlan`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PulseTrain {
    plan: TimerPlan,
    running: bool,
    event_pulses: u64,
    runs: u32,
}

impl PulseTrain {
    /// A stopped generator for `plan`, with zero counts.
    pub fn new(plan: TimerPlan) -> Self {
        Self {
            plan,
            running: false,
            event_pulses: 0,
            runs: 0,
        }
    }

    /// The plan in force.
    pub fn plan(&self) -> &TimerPlan {
        &self.plan
    }

    /// Replaces the plan (e.g. a new rate). Refused while running.
    pub fn set_plan(&mut self, plan: TimerPlan) -> Result<(), TrainError> {
        if self.running {
            return Err(TrainError::Running);
        }
        self.plan = plan;
        Ok(())
    }

    /// True between a successful [`start`](Self::start) and [`stop`](Self::stop).
    pub fn is_running(&self) -> bool {
        self.running
    }

    /// Number of runs started since power-up.
    pub fn runs(&self) -> u32 {
        self.runs
    }

    /// Starts a run: resets the counts (no pulse has begun until the first update) and returns
    /// the width, in ticks, to preload for event pulse 0 (the phase-coded width: pulse 0
    /// coincides with depth pulse 0).
    pub fn start(&mut self) -> Result<u16, TrainError> {
        if self.running {
            return Err(TrainError::AlreadyRunning);
        }
        self.running = true;
        self.event_pulses = 0;
        self.runs = self.runs.wrapping_add(1);
        Ok(self.plan.event_width_for(0))
    }

    /// Records that an event pulse has just begun (the slave timer's update; the first call of
    /// a run is pulse 0) and returns the width, in ticks, to preload for the pulse after it.
    /// Returns `None` while stopped (a stale interrupt after a stop changes nothing).
    pub fn on_event_pulse(&mut self) -> Option<u16> {
        if !self.running {
            return None;
        }
        let begun = self.event_pulses;
        self.event_pulses = begun.saturating_add(1);
        Some(self.plan.event_width_for(begun.saturating_add(1)))
    }

    /// Stops the run and returns its counts (which stay readable through
    /// [`counts`](Self::counts) until the next start).
    pub fn stop(&mut self) -> Result<PulseCounts, TrainError> {
        if !self.running {
            return Err(TrainError::NotRunning);
        }
        self.running = false;
        Ok(self.counts())
    }

    /// Pulses begun in the current (or last) run.
    pub fn counts(&self) -> PulseCounts {
        let per = u64::from(EVENT_PER_DEPTH);
        PulseCounts {
            event: self.event_pulses,
            depth: self.event_pulses.div_ceil(per),
        }
    }
}

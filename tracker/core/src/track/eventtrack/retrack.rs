//! Tracking again from a late depth frame's exposure. A live depth camera delivers a frame tens of milliseconds
//! after its exposure, so the ticks in between were tracked on events alone. When the frame arrives, the tracker
//! goes back to its state at the exposure tick (saved then), the event surface back to its events then, and
//! tracks those ticks again with the frame in place, as if it had come in time; then it tracks the current tick.
//! The poses already published for those ticks stand; from the current tick on, the estimates are the ones an
//! on-time frame would have given.
//!
//! The work is done when the frame arrives ([`EventTrack6d::retrack_on_arrival`], from `push_depth`): a live
//! camera's frame comes between two ticks, so the ticks tracked again then stay out of the next tick's latency
//! unless they take longer than the time left until it. A frame that cannot be placed then (no state at its
//! exposure, or its events left the log) is left to the next tick, which carries it and counts it.

use super::engine::TickEngine;
use super::inner::InnerPlan;
use crate::recon::SurfaceLog;
use crate::track::object::ObjectState;
use crate::track::{DepthFallbackCheck, PoseEstimate};
use drivers::timeline::Tick;
use scene::render::SceneObject;
use std::collections::VecDeque;

/// Where a frame handed over deferred is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Deferred {
    /// None waits.
    No,
    /// It waits for the next tick.
    BeforeTick,
    /// The tick carried the frame exposed then; tracking again from there waits for `prepare_next_tick`.
    AfterTick(i64),
    /// The next tick carries it, and it is not tracked again (the caller has fallen behind).
    CarryOnly,
}

/// The tracker's state at one depth-exposure tick, before that tick ran.
#[derive(Debug)]
struct ExposureState {
    tick: Tick,
    objects: Vec<ObjectState>,
    scene: Vec<SceneObject>,
    last_tick_us: Option<i64>,
    inner_since_tick: bool,
    /// Position of the event log then (the events pushed before the tick).
    events_before: u64,
}

/// What tracking again from a late frame's exposure needs: the states at recent depth-exposure ticks, the ticks
/// since the oldest, and the events since (with what each pixel held before them).
#[derive(Debug)]
pub(super) struct Retrack {
    /// States at depth-exposure ticks whose frame has not come yet, oldest first.
    states: VecDeque<ExposureState>,
    /// Slots of states no longer needed, reused for the next ones.
    spare: Vec<ExposureState>,
    /// The ticks since the oldest state, oldest first, each with the event log's position then.
    ticks: VecDeque<(Tick, u64)>,
    /// The events since the oldest state.
    pub(super) log: SurfaceLog,
    /// The poses of the ticks tracked again (not published: those ticks' poses are out already).
    replayed: Vec<PoseEstimate>,
    /// The depth safety net's checks made while tracking again before the latest tick, reported as that tick's.
    checks: Vec<DepthFallbackCheck>,
    /// Checks made while tracking again at a frame's arrival, reported with the next tick.
    arrival_checks: Vec<DepthFallbackCheck>,
    /// The earliest tick tracked again since the last [`Self::take_revision`], microseconds.
    revised_since: Option<i64>,
}

impl Retrack {
    /// Keeps at most `max_events` events (each 24 bytes).
    pub(super) fn new(max_events: usize) -> Self {
        Self {
            states: VecDeque::new(),
            spare: Vec::new(),
            ticks: VecDeque::new(),
            log: SurfaceLog::new(max_events),
            replayed: Vec::new(),
            checks: Vec::new(),
            arrival_checks: Vec::new(),
            revised_since: None,
        }
    }

    /// The earliest tick whose estimate was tracked again since the last call, microseconds.
    pub(super) fn take_revision(&mut self) -> Option<i64> {
        self.revised_since.take()
    }

    /// Whether any state is kept (events must then be logged).
    pub(super) fn is_logging(&self) -> bool {
        !self.states.is_empty()
    }

    /// Forgets the states older than `max_age_us` before `t_us`, and the ticks and events before the oldest
    /// state left.
    fn forget_before(&mut self, t_us: i64, max_age_us: i64) {
        while let Some(s) = self.states.front() {
            if t_us - s.tick.t_us <= max_age_us {
                break;
            }
            if let Some(s) = self.states.pop_front() {
                self.spare.push(s);
            }
        }
        let (oldest, position) = self
            .states
            .front()
            .map_or((t_us, self.log.end()), |s| (s.tick.t_us, s.events_before));
        while self.ticks.front().is_some_and(|(k, _)| k.t_us < oldest) {
            self.ticks.pop_front();
        }
        self.log.forget_before(position);
    }

    /// Forgets every saved state, tick and logged event (after a re-seed, nothing before it may come back).
    pub(super) fn forget_all(&mut self) {
        self.forget_from(i64::MIN);
        self.log.forget_before(self.log.end());
    }

    /// Forgets the states and ticks at or after `t_us`.
    fn forget_from(&mut self, t_us: i64) {
        while self.states.back().is_some_and(|s| s.tick.t_us >= t_us) {
            if let Some(s) = self.states.pop_back() {
                self.spare.push(s);
            }
        }
        while self.ticks.back().is_some_and(|(k, _)| k.t_us >= t_us) {
            self.ticks.pop_back();
        }
    }

    /// Drops the states of ticks at or before `t_us` (their frames were used).
    fn drop_states_until(&mut self, t_us: i64) {
        while self.states.front().is_some_and(|s| s.tick.t_us <= t_us) {
            if let Some(s) = self.states.pop_front() {
                self.spare.push(s);
            }
        }
    }
}

impl Retrack {
    /// When a depth frame arrives (it is waiting in `engine.depth_t_us`): if it was exposed at a tick already run
    /// whose state was saved, and the events since are still logged, tracks the ticks from that one to the latest
    /// again with the frame in place (the frame is used up). Returns whether it did: the next tick's renders are
    /// then to be started from the new estimates. Otherwise the frame waits for the next tick
    /// ([`Self::before_tick`]).
    pub(super) fn on_arrival(&mut self, engine: &mut TickEngine, inner: &mut InnerPlan) -> bool {
        let (Some(exposed_us), Some(last_us)) = (engine.depth_t_us, engine.last_tick_us) else {
            return false;
        };
        let max_age_us = (engine.config.late_depth.max_depth_age_ms * 1e3) as i64;
        let (times, count) = engine.next_tick.candidates();
        let next_us = if count > 0 {
            times[0]
        } else {
            last_us + engine.rig.clock.whole_period_us()
        };
        // The next tick would find the frame too old and drop it: it is not used here either.
        let fresh = next_us - exposed_us <= max_age_us;
        let Some(k) = self.start(engine, exposed_us).filter(|_| fresh) else {
            return false;
        };
        let mut checks = std::mem::take(&mut self.arrival_checks);
        self.track_again(engine, inner, k, last_us + 1, &mut checks);
        self.arrival_checks = checks;
        true
    }

    /// Forgets the checks made while tracking again at an arrival (a frame carried at a tick, tracked again
    /// after it: the tick reported its check).
    pub(super) fn forget_arrival_checks(&mut self) {
        self.arrival_checks.clear();
    }

    /// Before `tick` runs: if the depth frame waiting was exposed at an earlier tick whose state was saved, tracks
    /// the ticks from that one to this one again with the frame in place (the frame is used up), unless `defer`
    /// says otherwise; then saves the state if `tick` is a depth-exposure tick whose frame has not come. Returns
    /// what waits after the tick: [`Deferred::AfterTick`] for a frame handed over deferred that this tick carries.
    pub(super) fn before_tick(
        &mut self,
        engine: &mut TickEngine,
        inner: &mut InnerPlan,
        tick: &Tick,
        defer: Deferred,
    ) -> Deferred {
        let max_age_us = (engine.config.late_depth.max_depth_age_ms * 1e3) as i64;
        let half = engine.rig.clock.half_period_us();
        self.checks.clear();
        // Checks made when a frame arrived since the last tick are this tick's.
        let arrival_checks = self.arrival_checks.drain(..).map(|c| DepthFallbackCheck {
            tick_us: tick.t_us,
            ..c
        });
        self.checks.extend(arrival_checks);
        let mut after = Deferred::No;
        if let Some(exposed_us) = engine.depth_t_us
            && exposed_us < tick.t_us - half
            && tick.t_us - exposed_us <= max_age_us
        {
            match self.start(engine, exposed_us) {
                // This tick carries the frame; tracking again waits until its poses are out.
                Some(_) if defer == Deferred::BeforeTick => after = Deferred::AfterTick(exposed_us),
                // Carried at this tick only: counted like a frame that could not be tracked again.
                Some(_) if defer == Deferred::CarryOnly => {
                    engine.counters.late_frames_not_retracked += 1;
                }
                Some(k) => {
                    let mut checks = std::mem::take(&mut self.checks);
                    self.track_again(engine, inner, k, tick.t_us, &mut checks);
                    self.checks = checks;
                }
                None => engine.counters.late_frames_not_retracked += 1,
            }
        }
        let frame_here = engine
            .depth_t_us
            .is_some_and(|td| (td - tick.t_us).abs() <= half);
        // A clock that stood still or went back (a restarted replay) invalidates what was kept since.
        self.forget_from(tick.t_us);
        if tick.depth_frame.is_some() && !frame_here && max_age_us > 0 {
            self.save_before(engine, tick);
        }
        if self.is_logging() {
            self.ticks.push_back((*tick, self.log.end()));
        }
        self.forget_before(tick.t_us, max_age_us);
        after
    }

    /// Saves the engine's state before the depth-exposure `tick`, whose frame has not come, reusing a spare slot.
    fn save_before(&mut self, engine: &TickEngine, tick: &Tick) {
        let mut state = self.spare.pop().unwrap_or_else(|| ExposureState {
            tick: *tick,
            objects: engine.objects.iter().map(|o| o.state.clone()).collect(),
            scene: Vec::with_capacity(engine.scene.len()),
            last_tick_us: None,
            inner_since_tick: false,
            events_before: 0,
        });
        if self.states.is_empty() {
            // Events came unlogged until now: no earlier position is reachable.
            self.log.forget_before(self.log.end());
        }
        save_state(engine, tick, &mut state);
        state.events_before = self.log.end();
        self.states.push_back(state);
    }

    /// The index of the state saved at the tick of a frame exposed at `exposed_us`, if there is one and the event
    /// log still reaches back to it.
    fn start(&self, engine: &TickEngine, exposed_us: i64) -> Option<usize> {
        let half = engine.rig.clock.half_period_us();
        let k = self
            .states
            .iter()
            .position(|s| (s.tick.t_us - exposed_us).abs() <= half)?;
        self.log.reaches(self.states[k].events_before).then_some(k)
    }

    /// Tracks the ticks from the one of state `k` to just before `now_us` again, with the waiting depth frame used
    /// at the first of them, and leaves the surface at the latest event. The steps between ticks are planned
    /// again from the new estimates and run where their events are in, as they would have been with the frame on
    /// time; `inner` is left with the steps after the latest tick (those run and those to come). The safety
    /// net's checks made on the way go into `checks`, stamped `now_us`.
    fn track_again(
        &mut self,
        engine: &mut TickEngine,
        inner: &mut InnerPlan,
        k: usize,
        now_us: i64,
        checks: &mut Vec<DepthFallbackCheck>,
    ) {
        let start_us = self.states[k].tick.t_us;
        let wound = engine
            .surface
            .wind_back(&mut self.log, self.states[k].events_before);
        debug_assert!(
            wound,
            "retrack_start checked that the log reaches the state"
        );
        {
            let state = &self.states[k];
            for (o, s) in engine.objects.iter_mut().zip(&state.objects) {
                o.state.clone_from(s);
            }
            engine.scene.clone_from(&state.scene);
            engine.last_tick_us = state.last_tick_us;
            engine.inner_since_tick = state.inner_since_tick;
        }
        // The frame is treated as on time at its tick; what the replayed ticks count is not counted again.
        let counted = engine.counters;
        engine.depth_t_us = Some(start_us);
        let mut ticks = 0;
        let mut i = self.ticks.partition_point(|(t, _)| t.t_us < start_us);
        // The steps between ticks before the state's tick ran before it was saved.
        inner.clear();
        while let Some(&(tick, events_before)) = self.ticks.get(i) {
            if tick.t_us >= now_us {
                break;
            }
            self.step_between_ticks(engine, inner, events_before);
            engine.surface.wind_forward(&mut self.log, events_before);
            if tick.t_us > start_us
                && let Some(state) = self.states.iter_mut().find(|s| s.tick.t_us == tick.t_us)
            {
                // A later exposure's state, saved before this frame was in place: save it again.
                save_state(engine, &tick, state);
            }
            self.replayed.clear();
            engine.step_tick(&tick, &mut self.replayed, false);
            inner.plan(engine, tick.t_us);
            // The safety net's checks of the frame, made now: reported with the tick that made them.
            checks.extend(
                engine
                    .objects
                    .iter()
                    .filter_map(|o| o.state.fallback_check)
                    .filter(|c| c.tick_us == tick.t_us)
                    .map(|c| DepthFallbackCheck {
                        tick_us: now_us,
                        ..c
                    }),
            );
            ticks += 1;
            i += 1;
        }
        self.step_between_ticks(engine, inner, self.log.end());
        engine.surface.wind_forward(&mut self.log, u64::MAX);
        self.drop_states_until(start_us);
        engine.depth_t_us = None;
        engine.counters.ticks = counted.ticks;
        engine.counters.inner_steps = counted.inner_steps;
        engine.counters.depth_frames = counted.depth_frames + 1;
        engine.counters.depth_frames_late = counted.depth_frames_late + 1;
        engine.counters.depth_frames_unused = counted.depth_frames_unused;
        engine.counters.late_frames_retracked += 1;
        engine.counters.ticks_retracked += ticks;
        self.revised_since = Some(self.revised_since.map_or(start_us, |t| t.min(start_us)));
    }

    /// Runs the steps of `inner` not run yet whose events are in before log position `end`: a step runs once an
    /// event after its time is (as [`super::EventTrack6d`]'s `push_events` runs it), on the events up to its time.
    fn step_between_ticks(&mut self, engine: &mut TickEngine, inner: &mut InnerPlan, end: u64) {
        while let Some(t_us) = inner.next_time() {
            let after = self.log.position_after(t_us);
            if after >= end {
                break;
            }
            engine.surface.wind_forward(&mut self.log, after);
            inner.advance();
            engine.step_inner(t_us);
        }
    }

    /// The depth safety net's checks made while tracking again before the latest tick, reported as that tick's.
    pub(super) fn checks(&self) -> &[DepthFallbackCheck] {
        &self.checks
    }
}

/// Saves the engine's state before `tick` into `state`, reusing its buffers.
fn save_state(engine: &TickEngine, tick: &Tick, state: &mut ExposureState) {
    state.tick = *tick;
    for (o, s) in engine.objects.iter().zip(&mut state.objects) {
        s.clone_from(&o.state);
    }
    state.scene.clone_from(&engine.scene);
    state.last_tick_us = engine.last_tick_us;
    state.inner_since_tick = engine.inner_since_tick;
}

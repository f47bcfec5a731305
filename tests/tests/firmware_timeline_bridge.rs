//! Bridge between the trigger firmware and the tracker's timeline (issue 7, point 4).
//!
//! The firmware's own schedule core produces the edges the MCU emits; the event-line edges are
//! what the EVK4 records as `EXT_TRIGGER` words (channel 0, timestamps on its 1 us clock). They
//! are encoded as EVT3, decoded in chunks, and fed through `drivers::timeline::TriggerTimeline`;
//! the ticks must land on the 120 Hz rising edges and the depth-exposure ticks on the 30 Hz
//! pulses that trigger the depth camera, with phases 0, 1/4, 1/2, 3/4 between exposures.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use drivers::event::{CdEvent, EventBuffer, Geometry, TriggerEdge};
use drivers::formats::evt3::{Evt3Decoder, Evt3Encoder};
use drivers::timeline::{Tick, TimelineConfig, TriggerTimeline};
use firmware_trigger::{
    BOARD_TIMER_CLOCK_HZ, DEFAULT_DEPTH_HZ, EVENT_PER_DEPTH, Edge, EdgeSchedule, Line, PulseWidths,
    TimerPlan, rescale,
};

/// Seconds of schedule to run through the bridge (crosses two 24-bit EVT3 time wraps).
const RUN_S: u64 = 40;
/// Camera time of the first pulse, us: the MCU is started some time after the camera.
const T0_US: i64 = 10_000_123;

fn plan() -> TimerPlan {
    TimerPlan::new(
        BOARD_TIMER_CLOCK_HZ,
        DEFAULT_DEPTH_HZ,
        PulseWidths::default(),
    )
    .expect("board plan")
}

/// The firmware's edges over `RUN_S` seconds, on the camera's microsecond clock.
fn firmware_edges(plan: &TimerPlan) -> Vec<(Edge, i64)> {
    let end = RUN_S * u64::from(plan.tick_hz());
    EdgeSchedule::new(plan)
        .take_while(|e| e.t_ticks < end)
        .map(|e| {
            let t_us = T0_US + rescale(e.t_ticks, plan.tick_hz(), 1_000_000) as i64;
            (e, t_us)
        })
        .collect()
}

/// What the EVK4's trigger input sees: the event line only.
fn trigger_words(edges: &[(Edge, i64)]) -> Vec<TriggerEdge> {
    edges
        .iter()
        .filter(|(e, _)| e.line == Line::Event)
        .map(|(e, t_us)| TriggerEdge {
            t_us: *t_us,
            channel: 0,
            rising: e.rising,
        })
        .collect()
}

/// Sparse CD events between the triggers, so the decoder has to separate the two.
fn background_events() -> Vec<CdEvent> {
    (0..RUN_S as i64 * 500)
        .map(|i| CdEvent {
            t_us: T0_US + i * 2_000 + 37,
            x: (i * 7 % 1280) as u16,
            y: (i * 13 % 720) as u16,
            polarity: i % 3 == 0,
        })
        .collect()
}

/// EVT3 encode, decode in odd-sized chunks, return the decoded trigger edges.
fn through_evt3(triggers: &[TriggerEdge]) -> Vec<TriggerEdge> {
    let cd = background_events();
    let mut bytes = Vec::new();
    Evt3Encoder::new()
        .encode(&cd, triggers, &mut bytes)
        .expect("encodable");
    let mut decoder = Evt3Decoder::new(Some(Geometry::new(1280, 720)));
    let mut sink = EventBuffer::new();
    for chunk in bytes.chunks(4_093) {
        decoder.decode(chunk, &mut sink);
    }
    decoder.finish();
    assert_eq!(
        decoder.anomalies().total(),
        0,
        "clean stream decodes cleanly"
    );
    assert_eq!(sink.cd.len(), cd.len());
    sink.triggers
}

fn timeline_ticks(edges: &[TriggerEdge], config: TimelineConfig) -> (Vec<Tick>, TriggerTimeline) {
    let mut timeline = TriggerTimeline::new(config);
    let mut ticks = Vec::new();
    for &edge in edges {
        timeline.push(edge);
        while let Some(t) = timeline.pop_tick() {
            ticks.push(t);
        }
    }
    timeline.finish();
    while let Some(t) = timeline.pop_tick() {
        ticks.push(t);
    }
    (ticks, timeline)
}

#[test]
fn firmware_defaults_match_the_timeline_defaults() {
    let plan = plan();
    let derived = TimelineConfig {
        channel: 0,
        tick_rate_hz: f64::from(plan.event_hz()),
        ticks_per_depth: EVENT_PER_DEPTH,
        narrow_width_us: (plan.ticks_to_ns(u64::from(plan.event_width_ticks())) / 1_000) as i64,
        wide_width_us: (plan.ticks_to_ns(u64::from(plan.event_coded_width_ticks())) / 1_000) as i64,
        jitter_tolerance_us: TimelineConfig::default().jitter_tolerance_us,
        max_bridged_ticks: TimelineConfig::default().max_bridged_ticks,
    };
    assert_eq!(derived, TimelineConfig::default());
}

#[test]
fn firmware_schedule_through_evt3_gives_ticks_and_depth_phases() {
    let plan = plan();
    let edges = firmware_edges(&plan);
    let triggers = trigger_words(&edges);
    let decoded = through_evt3(&triggers);
    assert_eq!(
        decoded, triggers,
        "EVT3 round trip keeps every trigger edge"
    );

    let (ticks, timeline) = timeline_ticks(&decoded, TimelineConfig::default());
    let counters = *timeline.counters();
    let event_pulses = RUN_S * u64::from(plan.event_hz());
    assert_eq!(ticks.len() as u64, event_pulses);
    assert_eq!(counters.pulses, event_pulses);
    assert_eq!(counters.irregularities(), 0, "{counters:?}");

    // Ticks sit on the 120 Hz rising edges, numbered from 0.
    let event_rises: Vec<i64> = edges
        .iter()
        .filter(|(e, _)| e.line == Line::Event && e.rising)
        .map(|(_, t)| *t)
        .collect();
    for (k, tick) in ticks.iter().enumerate() {
        assert_eq!(tick.index, k as u64);
        assert_eq!(tick.t_us, event_rises[k], "tick {k}");
        assert!(!tick.synthesized);
    }

    // Depth exposure n is the 30 Hz pulse n: its tick carries frame n at the same time, and
    // the ticks between are at phases 1/4, 1/2, 3/4 of the depth period (to the 1 us clock).
    let depth_rises: Vec<i64> = edges
        .iter()
        .filter(|(e, _)| e.line == Line::Depth && e.rising)
        .map(|(_, t)| *t)
        .collect();
    assert_eq!(depth_rises.len() as u64, RUN_S * 30);
    let depth_period_us = 1e6 / f64::from(plan.depth_hz());
    for (k, tick) in ticks.iter().enumerate() {
        let n = k / EVENT_PER_DEPTH as usize;
        let phase = k % EVENT_PER_DEPTH as usize;
        if phase == 0 {
            assert_eq!(tick.depth_frame, Some(n as u64), "tick {k}");
            assert_eq!(tick.t_us, depth_rises[n], "depth exposure {n}");
        } else {
            assert_eq!(tick.depth_frame, None, "tick {k}");
        }
        let tau = (tick.t_us - depth_rises[n]) as f64 / depth_period_us;
        let expected = phase as f64 / f64::from(EVENT_PER_DEPTH);
        assert!(
            (tau - expected).abs() * depth_period_us <= 1.0,
            "tick {k}: tau {tau}, expected {expected}"
        );
    }
    // No drift across the run: the last depth exposure is where 30 Hz puts it.
    let last = depth_rises.len() - 1;
    assert_eq!(
        depth_rises[last] - T0_US,
        (last as f64 * depth_period_us).round() as i64
    );
}

#[test]
fn a_lost_pulse_is_bridged_and_depth_frames_stay_right() {
    let plan = plan();
    let edges = firmware_edges(&plan);
    // The event camera misses event pulse 9 (a plain pulse) and 12 (a phase-coded one).
    let triggers: Vec<TriggerEdge> = edges
        .iter()
        .filter(|(e, _)| e.line == Line::Event && e.index != 9 && e.index != 12)
        .map(|(e, t_us)| TriggerEdge {
            t_us: *t_us,
            channel: 0,
            rising: e.rising,
        })
        .collect();
    let decoded = through_evt3(&triggers);
    let (ticks, timeline) = timeline_ticks(&decoded, TimelineConfig::default());
    assert_eq!(ticks.len() as u64, RUN_S * u64::from(plan.event_hz()));
    assert_eq!(timeline.counters().missing, 2);
    assert!(ticks[9].synthesized && ticks[12].synthesized);
    assert_eq!(
        ticks[12].depth_frame,
        Some(3),
        "frame of a lost coded pulse from the schedule"
    );
    assert_eq!(ticks[16].depth_frame, Some(4));
    assert!(
        ticks
            .iter()
            .enumerate()
            .all(|(k, t)| t.index == k as u64 && (k % 4 == 0) == t.depth_frame.is_some())
    );
}

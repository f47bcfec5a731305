//! Host tests of the schedule core: exact plans, refusals, widths, phase code, start/stop and
//! counting, and no drift over an hour of pulses.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use firmware_trigger::edges::depth_index_of_event;
use firmware_trigger::plan::Pulse;
use firmware_trigger::{
    BOARD_TIMER_CLOCK_HZ, EVENT_PER_DEPTH, Edge, EdgeSchedule, Line, PlanError, PulseTrain,
    PulseWidths, TimerPlan, TrainError, rescale,
};

fn board_plan() -> TimerPlan {
    TimerPlan::new(BOARD_TIMER_CLOCK_HZ, 30, PulseWidths::default()).expect("84 MHz plans 30 Hz")
}

#[test]
fn board_clock_gives_the_design_register_values() {
    let plan = board_plan();
    assert_eq!(plan.prescaler(), 13, "84 MHz / 14 = 6 MHz tick");
    assert_eq!(plan.tick_hz(), 6_000_000);
    assert_eq!(plan.depth_reload(), 199_999);
    assert_eq!(plan.event_reload(), 49_999);
    assert_eq!(plan.depth_hz(), 30);
    assert_eq!(plan.event_hz(), 120);
    // 1 ms, 100 us, 200 us at 6 MHz.
    assert_eq!(plan.depth_width_ticks(), 6_000);
    assert_eq!(plan.event_width_ticks(), 600);
    assert_eq!(plan.event_coded_width_ticks(), 1_200);
}

#[test]
fn ratio_is_exactly_four_and_rates_exact_at_many_clocks() {
    let mut planned = 0;
    for clock in [
        84_000_000u32,
        168_000_000,
        48_000_000,
        96_000_000,
        72_000_000,
        1_200,
    ] {
        for depth_hz in [15u32, 30, 60] {
            let Ok(plan) = TimerPlan::new(
                clock,
                depth_hz,
                PulseWidths {
                    depth_ns: 1_000_000,
                    event_ns: 100_000,
                    event_coded_ns: 200_000,
                },
            ) else {
                continue;
            };
            planned += 1;
            let tick = u64::from(plan.tick_hz());
            assert_eq!(
                plan.depth_period_ticks(),
                EVENT_PER_DEPTH * plan.event_period_ticks()
            );
            assert_eq!(tick * (u64::from(plan.prescaler()) + 1), u64::from(clock));
            assert_eq!(
                u64::from(plan.event_period_ticks()) * u64::from(plan.event_hz()),
                tick,
                "event rate exact at {clock} Hz / {depth_hz} Hz"
            );
            assert_eq!(
                u64::from(plan.depth_period_ticks()) * u64::from(depth_hz),
                tick
            );
        }
    }
    // Every clock but the 1.2 kHz one (periods shorter than the widths) plans all three rates.
    assert_eq!(planned, 15);
}

#[test]
fn smallest_prescaler_that_fits_sixteen_bits_is_chosen() {
    // 48 MHz / 120 Hz = 400 000 cycles: dividers 7 (not a divisor)... 8 gives 50 000.
    let plan = TimerPlan::new(48_000_000, 30, PulseWidths::default()).unwrap();
    assert_eq!(plan.prescaler(), 7);
    assert_eq!(plan.event_reload(), 49_999);
    // 6 MHz / 120 Hz = 50 000 cycles fits without division.
    let plan = TimerPlan::new(6_000_000, 30, PulseWidths::default()).unwrap();
    assert_eq!(plan.prescaler(), 0);
    assert_eq!(plan.event_reload(), 49_999);
}

#[test]
fn refuses_clocks_where_rates_or_ratio_cannot_be_exact() {
    let w = PulseWidths::default();
    // QEMU mps2's 25 MHz: 30 Hz is not exact (no factor 3).
    assert_eq!(
        TimerPlan::new(25_000_000, 30, w),
        Err(PlanError::InexactDepthRate {
            clock_hz: 25_000_000,
            depth_hz: 30
        })
    );
    // The STM32's 16 MHz HSI: not a multiple of 30 either.
    assert!(matches!(
        TimerPlan::new(16_000_000, 30, w),
        Err(PlanError::InexactDepthRate { .. })
    ));
    // 30 Hz exact but 120 Hz not: 4:1 ratio cannot be met.
    assert_eq!(
        TimerPlan::new(84_000_030, 30, w),
        Err(PlanError::InexactRatio {
            clock_hz: 84_000_030,
            depth_hz: 30
        })
    );
    assert_eq!(TimerPlan::new(0, 30, w), Err(PlanError::Zero));
    assert_eq!(TimerPlan::new(84_000_000, 0, w), Err(PlanError::Zero));
    // Event period 120 * p cycles with p a prime above 65536: no prescaler fits 16 bits.
    let p = 65_537u32;
    assert_eq!(
        TimerPlan::new(120 * p, 30, w),
        Err(PlanError::NoPrescaler {
            event_period_cycles: u64::from(p)
        })
    );
    // Display names the problem.
    let msg = format!("{}", TimerPlan::new(84_000_030, 30, w).unwrap_err());
    assert!(msg.contains("4:1"), "{msg}");
}

#[test]
fn refuses_widths_the_cameras_or_periods_cannot_take() {
    let base = PulseWidths::default();
    let plan = |w| TimerPlan::new(BOARD_TIMER_CLOCK_HZ, 30, w);
    // RealSense needs more than 100 us.
    assert!(matches!(
        plan(PulseWidths {
            depth_ns: 100_000,
            ..base
        }),
        Err(PlanError::WidthTooShort {
            pulse: Pulse::Depth,
            ..
        })
    ));
    assert!(
        plan(PulseWidths {
            depth_ns: 100_001,
            ..base
        })
        .is_ok(),
        "100.001 us rounds up to whole ticks above 100 us"
    );
    // EVK4 needs at least 500 ns: 499 ns rounds up to 3 ticks = 500 ns at 6 MHz, accepted;
    // 1 ns at 6 MHz rounds up to one tick (166 ns), refused.
    assert!(matches!(
        plan(PulseWidths {
            event_ns: 1,
            event_coded_ns: 200_000,
            ..base
        }),
        Err(PlanError::WidthTooShort {
            pulse: Pulse::Event,
            ..
        })
    ));
    let ok = plan(PulseWidths {
        event_ns: 499,
        event_coded_ns: 1_000,
        ..base
    })
    .unwrap();
    assert_eq!(ok.event_width_ticks(), 3);
    assert_eq!(ok.ticks_to_ns(3), 500);
    // Widths that leave no low time.
    assert!(matches!(
        plan(PulseWidths {
            event_coded_ns: 8_333_334,
            ..base
        }),
        Err(PlanError::WidthTooLong {
            pulse: Pulse::EventCoded,
            ..
        })
    ));
    assert!(matches!(
        plan(PulseWidths {
            depth_ns: 40_000_000,
            ..base
        }),
        Err(PlanError::WidthTooLong {
            pulse: Pulse::Depth,
            ..
        })
    ));
    // Phase code must be distinguishable: at least 1.5 x.
    assert!(matches!(
        plan(PulseWidths {
            event_coded_ns: 149_000,
            ..base
        }),
        Err(PlanError::CodeNotDistinct { .. })
    ));
    assert!(
        plan(PulseWidths {
            event_coded_ns: 150_000,
            ..base
        })
        .is_ok()
    );
    // Rates too high for the widths are refused rather than overlapping pulses.
    assert!(matches!(
        TimerPlan::new(BOARD_TIMER_CLOCK_HZ, 1_500, base),
        Err(PlanError::WidthTooLong { .. })
    ));
}

#[test]
fn phase_code_marks_every_fourth_event_pulse_from_the_first() {
    let plan = board_plan();
    let widths: Vec<u16> = (0..12).map(|i| plan.event_width_for(i)).collect();
    assert_eq!(
        widths,
        [
            1200, 600, 600, 600, 1200, 600, 600, 600, 1200, 600, 600, 600
        ]
    );
    assert_eq!(depth_index_of_event(8), Some(2));
    assert_eq!(depth_index_of_event(9), None);
}

#[test]
fn start_stop_and_counting_follow_the_interrupt_sequence() {
    let plan = board_plan();
    let mut train = PulseTrain::new(plan);
    assert!(!train.is_running());
    assert_eq!(
        train.on_event_pulse(),
        None,
        "stale interrupt while stopped"
    );
    assert_eq!(train.stop(), Err(TrainError::NotRunning));

    // Pulse 0's width is preloaded at start; the update interrupt at the start of pulse k
    // (pulse 0 included) returns the width for pulse k + 1.
    assert_eq!(train.start(), Ok(1200));
    assert_eq!(
        train.counts().event,
        0,
        "nothing begun before the first update"
    );
    assert_eq!(train.start(), Err(TrainError::AlreadyRunning));
    assert_eq!(train.set_plan(plan), Err(TrainError::Running));
    let mut preloaded = vec![1200u16];
    for _ in 0..10 {
        preloaded.push(train.on_event_pulse().unwrap());
    }
    for (k, w) in preloaded.iter().enumerate() {
        assert_eq!(*w, plan.event_width_for(k as u64), "pulse {k}");
    }
    // Ten updates: pulses 0..=9 begun, depth pulses with event pulses 0, 4, 8.
    let counts = train.counts();
    assert_eq!((counts.event, counts.depth), (10, 3));
    assert_eq!(train.stop().map(|c| (c.event, c.depth)), Ok((10, 3)));
    assert_eq!(train.on_event_pulse(), None);
    assert_eq!(train.counts().event, 10, "counts stay readable after stop");

    // A restart begins again at pulse 0 with the coded width.
    assert_eq!(train.start(), Ok(1200));
    assert_eq!(train.counts().event, 0);
    assert_eq!(train.counts().depth, 0);
    assert_eq!(train.on_event_pulse(), Some(600));
    assert_eq!(train.counts().depth, 1);
    assert_eq!(train.runs(), 2);
}

#[test]
fn edges_are_ordered_and_phase_locked() {
    let plan = board_plan();
    let edges: Vec<Edge> = EdgeSchedule::new(&plan).take(40).collect();
    let key = |e: &Edge| (e.t_ticks, e.line, e.rising, e.index);
    // First rising edges together at tick 0, depth listed first.
    assert_eq!(key(&edges[0]), (0, Line::Depth, true, 0));
    assert_eq!(key(&edges[1]), (0, Line::Event, true, 0));
    assert_eq!(key(&edges[2]), (1_200, Line::Event, false, 0));
    assert_eq!(key(&edges[3]), (6_000, Line::Depth, false, 0));
    assert_eq!(key(&edges[4]), (50_000, Line::Event, true, 1));
    assert_eq!(key(&edges[5]), (50_600, Line::Event, false, 1));
    assert!(edges.windows(2).all(|w| w[0].t_ticks <= w[1].t_ticks));
    for e in &edges {
        if e.line == Line::Event {
            assert_eq!(e.coded, e.index % 4 == 0);
        }
    }
}

/// One hour of the board's schedule: every rising edge sits exactly on `k / rate` seconds
/// (integer arithmetic, no tolerance), every width is exact, every 4th event edge coincides
/// with a depth edge, and the counts come out as 3600 x rate.
#[test]
fn no_drift_over_an_hour() {
    let plan = board_plan();
    let tick = u64::from(plan.tick_hz());
    let hour_ticks = 3_600 * tick;
    let (mut depth_rises, mut event_rises) = (0u64, 0u64);
    let mut last_rise = [0u64; 2];
    let mut train = PulseTrain::new(plan);
    // Width preloaded for the next event pulse, and the width of the pulse in progress.
    let mut preload = train.start().unwrap();
    let mut current = 0u16;
    for e in EdgeSchedule::new(&plan).take_while(|e| e.t_ticks < hour_ticks) {
        let slot = e.line as usize;
        if e.rising {
            last_rise[slot] = e.t_ticks;
            match e.line {
                Line::Depth => {
                    assert_eq!(
                        e.t_ticks * 30,
                        depth_rises * tick,
                        "depth pulse {depth_rises}"
                    );
                    depth_rises += 1;
                }
                Line::Event => {
                    assert_eq!(
                        e.t_ticks * 120,
                        event_rises * tick,
                        "event pulse {event_rises}"
                    );
                    // What the board's update interrupt does at this edge.
                    current = preload;
                    preload = train.on_event_pulse().unwrap();
                    event_rises += 1;
                }
            }
        } else {
            let width = e.t_ticks - last_rise[slot];
            let expected = match e.line {
                Line::Depth => u64::from(plan.depth_width_ticks()),
                Line::Event => {
                    assert_eq!(width, u64::from(current), "preloaded width of {}", e.index);
                    u64::from(plan.event_width_for(e.index))
                }
            };
            assert_eq!(width, expected, "{:?} pulse {} width", e.line, e.index);
        }
    }
    assert_eq!(depth_rises, 3_600 * 30);
    assert_eq!(event_rises, 3_600 * 120);
    let counts = train.stop().unwrap();
    assert_eq!((counts.event, counts.depth), (3_600 * 120, 3_600 * 30));
}

#[test]
fn rescaling_to_another_clock_stays_within_one_cycle_without_accumulating() {
    // The QEMU variant replays 6 MHz ticks on mps2's 25 MHz clock.
    let plan = board_plan();
    let (from, to) = (plan.tick_hz(), 25_000_000u32);
    let period = u64::from(plan.event_period_ticks());
    let mut prev = rescale(0, from, to);
    for k in 1..=120 * 60u64 {
        let t = rescale(k * period, from, to);
        let d = t - prev;
        assert!(d == 208_333 || d == 208_334, "period {k}: {d} cycles");
        // Absolute error under half a cycle: exact value is k * 625000 / 3.
        let exact_x3 = k * 625_000;
        assert!((t * 3).abs_diff(exact_x3) <= 1, "edge {k}");
        prev = t;
    }
    assert_eq!(rescale(600, from, to), 2_500, "100 us is exact");
    assert_eq!(
        rescale(5, 0, to),
        0,
        "zero clock gives no time, not a panic"
    );
}

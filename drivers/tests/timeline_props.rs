//! Property tests of the trigger timeline under dropped, extra and jittered pulses.

use drivers::event::TriggerEdge;
use drivers::timeline::{TickIter, TimelineConfig, ideal_edges};
use proptest::prelude::*;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// Whatever is dropped or jittered, ticks are consecutive, time-ordered, and every kept depth pulse
    /// still gets its true depth frame number once the phase is locked.
    #[test]
    fn ticks_stay_consecutive_and_depth_frames_stay_true(
        drops in proptest::collection::vec(any::<bool>(), 400),
        jitter in proptest::collection::vec(-30i64..30, 400),
    ) {
        let cfg = TimelineConfig::default();
        let ideal = ideal_edges(&cfg, 10_000, 400);
        let mut edges = Vec::new();
        for (i, pair) in ideal.chunks(2).enumerate() {
            // Keep the first pulse (wide, so the phase locks immediately); drop about 1 in 8 of the rest.
            if i > 0 && drops[i] && drops[(i * 7) % 400] && drops[(i * 13) % 400] {
                continue;
            }
            for e in pair {
                edges.push(TriggerEdge { t_us: e.t_us + jitter[i], ..*e });
            }
        }
        let kept: Vec<i64> = edges.iter().filter(|e| e.rising).map(|e| e.t_us).collect();
        let mut it = TickIter::new(cfg, edges.into_iter());
        let ticks: Vec<_> = it.by_ref().collect();
        let c = *it.timeline().counters();
        let last_kept_index = ((kept.last().unwrap() - 10_000) as f64 / cfg.period_us()).round() as u64;
        prop_assert_eq!(ticks.len() as u64, last_kept_index + 1);
        prop_assert_eq!(c.pulses as usize, kept.len());
        prop_assert_eq!(c.missing as usize, ticks.len() - kept.len());
        for (i, t) in ticks.iter().enumerate() {
            prop_assert_eq!(t.index, i as u64);
            prop_assert_eq!(t.depth_frame, (i % 4 == 0).then_some(i as u64 / 4));
            if i > 0 {
                prop_assert!(t.t_us > ticks[i - 1].t_us);
            }
        }
    }

    /// Arbitrary edge soup never panics and never yields out-of-order tick indices.
    #[test]
    fn arbitrary_edges_never_break_the_timeline(
        raw in proptest::collection::vec((0i64..20_000, 0u8..3, any::<bool>()), 0..300)
    ) {
        let mut t = 0;
        let edges: Vec<TriggerEdge> = raw.into_iter().map(|(gap, channel, rising)| {
            t += gap;
            TriggerEdge { t_us: t, channel, rising }
        }).collect();
        let ticks: Vec<_> = TickIter::new(TimelineConfig::default(), edges.into_iter()).collect();
        for w in ticks.windows(2) {
            prop_assert_eq!(w[1].index, w[0].index + 1);
            prop_assert!(w[1].t_us >= w[0].t_us);
        }
    }
}

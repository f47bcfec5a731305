//! The event term's binning, done ahead of the ROI render (`EventEdges::bin_ahead`), gives the same bins as
//! binning inside `collect`, and is used only for the window it was made for.

#![allow(clippy::unwrap_used, clippy::expect_used)]

#[path = "../../scene/tests/common/mod.rs"]
mod common;

use drivers::event::CdEvent;
use nalgebra::Point3;
use scene::geometry::Roi;
use tracker::recon::{EventSurface, IntensityFilterConfig};
use tracker::refine::{BinnedWindow, EventEdges, EventTerm, EventTermStats};

/// A surface whose left half fired at 4 ms and right half at 9.5 ms, and a ROI over its middle.
fn scene() -> (EventSurface, Roi) {
    let cam = common::vga();
    let events: Vec<CdEvent> = (0..cam.height)
        .flat_map(|y| (0..cam.width).map(move |x| (x, y)))
        .map(|(x, y)| CdEvent {
            t_us: if x < cam.width / 2 { 4_000 } else { 9_500 },
            x: x as u16,
            y: y as u16,
            polarity: true,
        })
        .collect();
    let mut surface = EventSurface::new(cam.width, cam.height, IntensityFilterConfig::default());
    surface.integrate(&events);
    let roi = Roi::around_object(&cam, &Point3::new(0.0, 0.0, 0.5), 0.17, 1.2, 160).unwrap();
    (surface, roi)
}

/// Stats of a `collect` at 10 ms over `window_us`, handed `prebinned`.
fn collect(
    edges: &mut EventEdges,
    surface: &EventSurface,
    roi: &Roi,
    window_us: i64,
    prebinned: Option<BinnedWindow>,
) -> EventTermStats {
    edges.collect(
        &EventTerm::default(),
        surface,
        roi,
        &[],
        &[],
        f32::NEG_INFINITY,
        1,
        10_000,
        window_us,
        400,
        prebinned,
    );
    edges.stats()
}

#[test]
fn bins_made_ahead_equal_bins_made_in_collect_and_only_for_their_window() {
    let (surface, roi) = scene();
    let short = collect(&mut EventEdges::default(), &surface, &roi, 1_000, None);
    let long = collect(&mut EventEdges::default(), &surface, &roi, 8_000, None);
    // The windows see different events: the short one only the right half.
    assert!(short.bins > 1000, "{short:?}");
    assert!(long.bins > short.bins + 1000, "{long:?} against {short:?}");

    // Binned ahead for the same window: the same result.
    let window = |window_us| BinnedWindow {
        t_us: 10_000,
        window_us,
        roi,
    };
    let mut edges = EventEdges::default();
    edges.bin_ahead(&surface, window(1_000));
    let prebinned = edges.take_prebinned();
    assert_eq!(prebinned, Some(window(1_000)));
    assert_eq!(edges.take_prebinned(), None, "taken once");
    assert_eq!(collect(&mut edges, &surface, &roi, 1_000, prebinned), short);

    // Binned ahead for another window: collect bins again rather than use the wrong events.
    let mut edges = EventEdges::default();
    edges.bin_ahead(&surface, window(8_000));
    let prebinned = edges.take_prebinned();
    assert_eq!(collect(&mut edges, &surface, &roi, 1_000, prebinned), short);
    let mut edges = EventEdges::default();
    edges.bin_ahead(&surface, window(1_000));
    let prebinned = edges.take_prebinned();
    assert_eq!(collect(&mut edges, &surface, &roi, 8_000, prebinned), long);
}

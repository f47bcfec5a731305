//! The tick at the first pose's own time ([`tracker::track::CorrespondConfig::events_at_first_pose`]): with the
//! option off it refines on its depth frame alone, and the events take part from the next tick on.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use drivers::recording::Recording;
use eventtrack6d_tests::tick_fixture::{fast_mug_recording, mug_estimates};
use tracker::track::{CorrespondConfig, ModalityConfig, PoseEstimate, TrackerConfig};

/// Every estimate of `rec` tracked from the mug's first ground-truth pose with `config`.
fn track(rec: &Recording, config: TrackerConfig) -> Vec<PoseEstimate> {
    mug_estimates(rec, config)
}

fn with(events_at_first_pose: bool, events: bool) -> TrackerConfig {
    TrackerConfig {
        correspond: CorrespondConfig {
            events_at_first_pose,
            ..CorrespondConfig::default()
        },
        modalities: ModalityConfig {
            events,
            ..ModalityConfig::default()
        },
        ..TrackerConfig::default()
    }
}

/// Off, the first tick's estimate is the one the tracker makes without events, bit for bit, and the ticks after
/// it are not (the events take part there); on (the default), the events take part at the first tick too.
#[test]
fn the_first_pose_tick_refines_on_depth_alone_when_asked() {
    let dir = tempfile::tempdir().unwrap();
    let rec = fast_mug_recording(&dir.path().join("fast"), 0.2);
    let without_events = track(&rec, with(true, false));
    let depth_first = track(&rec, with(false, true));
    let with_events = track(&rec, with(true, true));
    assert!(depth_first.len() > 10, "{} estimates", depth_first.len());
    assert_eq!(depth_first[0].t_us, without_events[0].t_us);
    assert_eq!(depth_first[0].pose, without_events[0].pose);
    assert_ne!(with_events[0].pose, without_events[0].pose);
    assert_ne!(depth_first[1].pose, without_events[1].pose);
}

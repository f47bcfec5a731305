//! An object whose mesh has more triangles than `render_mesh_simplify_above` is rendered simplified within
//! `render_mesh_tolerance_px`, and the tracker still follows it; meshes up to the threshold, or any mesh with a
//! zero tolerance, render as loaded.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use eventtrack6d_tests::tick_fixture::mug_recording;
use scene::mesh::Simplification;
use scene::render::CpuRenderer;
use tracker::recording::{PoseTrack, recording_ticks};
use tracker::recording::{recording_object, recording_rig};
use tracker::track::{EventTrack6d, ExecutionConfig, TrackerConfig, track_recording};

/// Tracks the fixture's 0.5 s mug shake with `config`: how the mesh was simplified, the mug's diameter, and the
/// mean and largest distance between the estimated and true positions, metres.
fn track_mug(config: TrackerConfig) -> (Simplification, f64, f64, f64) {
    let dir = std::env::temp_dir().join("eventtrack6d-render-mesh-test");
    let recording = mug_recording(&dir, 0.5);
    let truth = PoseTrack::from_samples(recording.ground_truth.as_deref().unwrap(), "mug");
    let first = recording_ticks(&recording).unwrap()[0].t_us;
    let pose = truth.interpolated_at(first).unwrap();
    let mug = recording_object(&recording, "mug", first, pose).unwrap();
    let diameter = mug.diameter;
    let rig = recording_rig(&recording).unwrap();
    let mut tracker =
        EventTrack6d::new(config, rig, vec![mug], Box::new(CpuRenderer::new())).unwrap();
    let simplification = tracker.render_meshes()[0];
    let mut errors = Vec::new();
    track_recording(
        &recording,
        &mut tracker,
        first,
        |_, estimates, _| {
            let e = &estimates[0];
            if let Some(t) = truth.interpolated_at(e.t_us) {
                errors.push((e.pose.translation.vector - t.translation.vector).norm());
            }
        },
        |_| {},
    )
    .unwrap();
    assert!(
        errors.len() > 50,
        "{} ticks with ground truth",
        errors.len()
    );
    let mean = errors.iter().sum::<f64>() / errors.len() as f64;
    let worst = errors.iter().copied().fold(0.0, f64::max);
    (simplification, diameter, mean, worst)
}

#[test]
fn a_dense_mesh_is_rendered_simplified_and_still_tracked() {
    // The library mug has 1,896 triangles: as loaded at the defaults.
    let (loaded, diameter, loaded_mean, loaded_worst) = track_mug(TrackerConfig::default());
    assert_eq!(loaded.triangles_before, 1896);
    assert_eq!(loaded.triangles_after, loaded.triangles_before);
    assert_eq!(loaded.largest_error_m, 0.0);

    // Counted as dense: simplified within a quarter of an ROI pixel (1.2 diameters over 160 pixels).
    let config = TrackerConfig {
        execution: ExecutionConfig {
            render_mesh_simplify_above: 1000,
            ..Default::default()
        },
        ..TrackerConfig::default()
    };
    let tolerance_m =
        config.execution.render_mesh_tolerance_px * config.roi.roi_scale * diameter / 160.0;
    let (simple, _, mean, worst) = track_mug(config);
    assert_eq!(simple.triangles_before, 1896);
    assert!(
        simple.triangles_after * 2 < simple.triangles_before,
        "{simple:?}"
    );
    assert!(
        simple.largest_error_m > 0.0 && simple.largest_error_m <= tolerance_m * 1.01,
        "{simple:?} against {tolerance_m} m"
    );
    eprintln!(
        "as loaded: mean {loaded_mean} m, worst {loaded_worst} m; simplified: mean {mean} m, worst {worst} m"
    );
    // Here both follow the mug within 2.6-2.7 mm on average, 8.1 mm at worst.
    assert!(
        mean < loaded_mean + 0.001 && worst < 0.015,
        "simplified: mean {mean} m, worst {worst} m"
    );

    // A zero tolerance renders any mesh as loaded.
    let (zero, _, _, _) = track_mug(TrackerConfig {
        execution: ExecutionConfig {
            render_mesh_simplify_above: 0,
            render_mesh_tolerance_px: 0.0,
            ..Default::default()
        },
        ..TrackerConfig::default()
    });
    assert_eq!(zero.triangles_after, zero.triangles_before);
}

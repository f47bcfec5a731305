//! The ROS 2 source end to end: `hil-sim ros2-play` publishes a generated recording as metavision_driver and
//! realsense-ros would (EventPacket slices of 1 ms, depth Image and CameraInfo at 30 Hz, rmw_zenoh keys), the
//! runtime reads them through `[source] kind = "ros2"`, and the poses are the offline tracker's on the same
//! recording, bit for bit (nothing is dropped on loopback with the player's blocking publishers).

#![allow(clippy::unwrap_used, clippy::expect_used)]

use eventtrack6d::runtime::ros2::{PlaybackEndpoints, playback_config};
use eventtrack6d::runtime::setup::recording_scene;
use eventtrack6d::runtime::{self, Hooks, build_tracker};
use eventtrack6d_tests::replay_counters::assert_counters_match_offline;
use eventtrack6d_tests::tick_fixture::{mug_and_can_recording, offline_pose_rows};
use eventtrack6d_tests::zenoh_run::free_port;
use hil_sim::ros2_play::{Pace, Ros2PlayOptions, SessionMode, SessionOptions, Topics, play};
use scene::render::RendererKind;
use std::time::Duration;
use tracker::recording::parse_pose_csv;
use tracker::track::{OfflineTiming, TrackerConfig};

#[test]
fn ros2_play_into_the_ros2_source_gives_the_offline_poses_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let rec_dir = dir.path().join("rec");
    let rec = mug_and_can_recording(&rec_dir);

    // The configuration `eventtrack6d ros2-config` writes: the recording's calibration and schedule, its objects
    // at their ground-truth poses at the first tick as configured objects (what a ROS 2 user gives).
    let s = rec.meta.trigger;
    let port = free_port();
    let out_dir = dir.path().join("out");
    let endpoints = PlaybackEndpoints {
        connect: Vec::new(),
        listen: vec![format!("tcp/127.0.0.1:{port}")],
    };
    let toml = playback_config(&rec, &endpoints, &out_dir).unwrap();
    let mut config = runtime::config::from_toml(&toml, "ros2.toml").unwrap();
    assert_eq!(config.objects.len(), 2, "{toml}");
    config.ros2.as_mut().unwrap().wait_for_data_s = 120.0;
    config.sinks.zenoh = false;
    // Small event batches, so that batch edges fall everywhere.
    config.queue.batch_us = 53;

    // Offline, on the same configured objects.
    let scene = recording_scene(&rec, &config.objects).unwrap();
    let mut tracker = build_tracker(
        "eventtrack6d",
        RendererKind::Cpu,
        &TrackerConfig::default(),
        &scene,
        &s.timeline_config(),
    )
    .unwrap();
    let timing = OfflineTiming {
        start_us: scene.objects[0].first_pose.0,
        depth_latency_us: 0,
        depth_jitter_us: 0,
    };
    let (offline, stats) = offline_pose_rows(&rec, tracker.as_mut(), timing);
    assert!(stats.depth_frames >= 11, "{stats:?}");

    // The runtime waits for the first pulse on the ROS 2 topics; the player waits for its subscription.
    let runner = std::thread::spawn(move || runtime::run(&config, Hooks::default()));
    let offset_ns = 1_700_000_000_000_000_000i64;
    let options = Ros2PlayOptions {
        recording: rec_dir.clone(),
        pace: Pace::Fast,
        slice_us: 1000,
        depth_latency_us: 0,
        session: SessionOptions {
            mode: SessionMode::Peer,
            connect: vec![format!("tcp/127.0.0.1:{port}")],
            listen: Vec::new(),
        },
        domain_id: 0,
        topics: Topics {
            events: "/event_camera/events".into(),
            depth_image: "/camera/camera/depth/image_rect_raw".into(),
            camera_info: "/camera/camera/depth/camera_info".into(),
            event_frame_id: "event_camera_optical_frame".into(),
            depth_frame_id: "camera_depth_optical_frame".into(),
        },
        stamp_offset_ns: Some(offset_ns),
        wait_for_subscriber: Duration::from_secs(120),
        progress: false,
    };
    let played = play(&options).expect("ros2-play");
    let summary = runner.join().unwrap().expect("the ROS 2 run failed");

    let ros2 = summary.source_stats.ros2.clone().expect("ROS 2 counters");
    assert_eq!(ros2.packets, played.packets, "{summary}");
    assert_eq!(ros2.bytes, played.bytes);
    assert_eq!((ros2.packets_missing, ros2.packets_out_of_order), (0, 0));
    assert!(ros2.unusable.is_empty(), "{:?}", ros2.unusable);
    assert_eq!(ros2.depth_images, played.depth_frames);
    assert_eq!(ros2.camera_infos, played.depth_frames);
    // The stamps' offset, estimated from the packets, is the player's to within a packet's first event.
    let estimated = ros2.clock_offset_ns.unwrap();
    assert!(
        (offset_ns - 1_000_000..=offset_ns).contains(&estimated),
        "{estimated}"
    );
    assert_eq!(summary.source_stats.depth_frames, stats.depth_frames);
    assert!(
        summary.to_string().contains("ros2:            "),
        "{summary}"
    );

    let csv = std::fs::read_to_string(summary.outputs.csv.clone().unwrap()).unwrap();
    let received: Vec<&str> = csv.lines().skip(1).collect();
    assert_eq!(received.len(), offline.len());
    let moving = parse_pose_csv(&csv)
        .unwrap()
        .windows(4)
        .any(|w| (w[0].pose.translation.vector - w[2].pose.translation.vector).norm() > 1e-3);
    assert!(
        moving,
        "the scene must move for the comparison to mean anything"
    );
    for (r, o) in received.iter().zip(&offline) {
        assert_eq!(
            *r, o,
            "the ROS 2 run's estimate differs from the offline one"
        );
    }
    assert_counters_match_offline(
        &summary.tracker.expect("the run counts"),
        &tracker.tracker_counters().expect("the tracker counts"),
        TrackerConfig::default().inner_steps.max_inner_steps,
        scene.objects.len() as u64,
        false,
    );
}

//! `ros2-play` seen from a separate zenoh session, as a ROS 2 node under rmw_zenoh would see it: a generated
//! recording played as fast as possible to a subscriber that announces itself with an rmw_zenoh subscription
//! token; every message decoded and checked against the recording. Loopback only, multicast scouting off, ports
//! picked free at run time.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod ros2_play_checks;

use drivers::recording::Recording;
use hil_sim::generate::{GenerateConfig, ObjectSource, generate};
use hil_sim::motion::{MotionProfile, SpeedLevel};
use hil_sim::objects::ObjectKind;
use hil_sim::ros2_play::{
    Pace, Ros2PlayError, Ros2PlayOptions, SessionMode, SessionOptions, Topics, play,
};
use ros2::types::{CAMERA_INFO, EVENT_PACKET, IMAGE};
use ros2::{Attachment, EntityKind, RosNodeIdentity};
use std::net::TcpListener;
use std::path::Path;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use zenoh::Wait;

use ros2_play_checks::{
    OFFSET_NS, Received, SLICE_US, check_depth, check_event_packets, wide_rises,
};

/// A TCP port on 127.0.0.1 that nothing listens on right now.
fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

/// A peer session that listens on `endpoint`, connects nowhere, with multicast scouting off.
fn listening_session(endpoint: &str) -> zenoh::Session {
    let mut c = zenoh::Config::default();
    c.insert_json5("mode", "\"peer\"").unwrap();
    c.insert_json5("listen/endpoints", &format!("[\"{endpoint}\"]"))
        .unwrap();
    c.insert_json5("connect/endpoints", "[]").unwrap();
    c.insert_json5("scouting/multicast/enabled", "false")
        .unwrap();
    zenoh::open(c).wait().unwrap()
}

fn options(recording: &Path, endpoint: &str, wait: Duration) -> Ros2PlayOptions {
    Ros2PlayOptions {
        recording: recording.to_path_buf(),
        pace: Pace::Fast,
        slice_us: SLICE_US,
        depth_latency_us: 0,
        session: SessionOptions {
            mode: SessionMode::Peer,
            connect: vec![endpoint.to_owned()],
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
        stamp_offset_ns: Some(OFFSET_NS),
        wait_for_subscriber: wait,
        progress: false,
    }
}

#[test]
fn a_recording_reaches_a_ros2_subscriber_byte_for_byte() {
    let dir = tempfile::tempdir().unwrap();
    let mut config = GenerateConfig::new(
        ObjectSource::Library(ObjectKind::Can),
        MotionProfile::Translation,
        SpeedLevel::Moderate,
        0.2,
        11,
    );
    config.depth_drop_probability = 0.25;
    generate(&config, dir.path(), |_| {}).unwrap();
    let rec = Recording::open(dir.path()).unwrap();
    assert!(rec.depth_frames.len() >= 3, "{:?}", rec.depth_frames);

    let endpoint = format!("tcp/127.0.0.1:{}", free_port());
    let session = listening_session(&endpoint);
    let received: Arc<Mutex<Vec<Received>>> = Arc::default();
    let sink = Arc::clone(&received);
    let _data = session
        .declare_subscriber("0/**")
        .callback(move |s| {
            let att = Attachment::from_bytes(&s.attachment().unwrap().to_bytes()).unwrap();
            let item = (
                s.key_expr().to_string(),
                s.payload().to_bytes().to_vec(),
                att,
            );
            sink.lock().unwrap().push(item);
        })
        .wait()
        .unwrap();
    let tokens: Arc<Mutex<Vec<String>>> = Arc::default();
    let token_sink = Arc::clone(&tokens);
    let _graph = session
        .liveliness()
        .declare_subscriber("@ros2_lv/0/**/MP/**")
        .callback(move |s| token_sink.lock().unwrap().push(s.key_expr().to_string()))
        .wait()
        .unwrap();
    let me = RosNodeIdentity {
        domain_id: 0,
        zid: session.zid().to_string(),
        node_id: 0,
        enclave: "/".into(),
        namespace: "/".into(),
        name: "listener".into(),
    };
    let sub_token = ros2::entity_liveliness_key_expr(
        &me,
        1,
        EntityKind::Subscription,
        "/event_camera/events",
        &EVENT_PACKET,
        ros2::DEFAULT_QOS_KEY,
    );
    let _token = session
        .liveliness()
        .declare_token(sub_token)
        .wait()
        .unwrap();

    let summary = play(&options(dir.path(), &endpoint, Duration::from_secs(10))).unwrap();
    let expected = summary.packets as usize + 2 * summary.depth_frames as usize;
    let deadline = Instant::now() + Duration::from_secs(10);
    while received.lock().unwrap().len() < expected && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(20));
    }
    let received = received.lock().unwrap();
    assert_eq!(received.len(), expected);
    assert_eq!(summary.depth_frames as usize, rec.depth_frames.len());
    assert_eq!(summary.depth_from_schedule, 0);

    let on = |topic: &str, ty| -> Vec<&Received> {
        let key = ros2::typed_key_expr(0, topic, ty);
        received.iter().filter(|r| r.0 == key).collect()
    };
    let packets = on("/event_camera/events", &EVENT_PACKET);
    assert_eq!(packets.len() as u64, summary.packets);
    let latest = check_event_packets(&rec, &packets);
    let images = on("/camera/camera/depth/image_rect_raw", &IMAGE);
    let infos = on("/camera/camera/depth/camera_info", &CAMERA_INFO);
    check_depth(&rec, &images, &infos);
    // Each frame arrives before the packet holding its exposure (the rising edge of its pulse), with no latency.
    let position = |r: &Received| received.iter().position(|x| std::ptr::eq(x, r)).unwrap();
    let rises = wide_rises(&rec);
    for (i, &k) in rec.depth_frames.iter().enumerate() {
        let holder = latest
            .iter()
            .position(|t| t.is_some_and(|t| t >= rises[k as usize]))
            .unwrap();
        assert!(position(images[i]) < position(infos[i]));
        assert!(
            position(infos[i]) < position(packets[holder]),
            "frame {k} after its packet"
        );
        if holder > 0 {
            assert!(
                position(images[i]) > position(packets[holder - 1]),
                "frame {k} early"
            );
        }
    }
    // One GID per publisher.
    let mut gids: Vec<_> = received.iter().map(|r| r.2.gid).collect();
    gids.sort_unstable();
    gids.dedup();
    assert_eq!(gids.len(), 3);

    let tokens = tokens.lock().unwrap();
    for topic in [
        "%event_camera%events",
        "%camera%camera%depth%image_rect_raw",
        "%camera%camera%depth%camera_info",
    ] {
        assert!(
            tokens
                .iter()
                .any(|t| t.contains("/hil_sim_ros2_play/") && t.contains(topic)),
            "no publisher token for {topic}: {tokens:?}"
        );
    }
}

#[test]
fn without_a_subscription_it_fails_naming_the_topic_and_domain() {
    let dir = tempfile::tempdir().unwrap();
    let config = GenerateConfig::new(
        ObjectSource::Library(ObjectKind::Can),
        MotionProfile::Translation,
        SpeedLevel::Slow,
        0.05,
        3,
    );
    generate(&config, dir.path(), |_| {}).unwrap();
    let endpoint = format!("tcp/127.0.0.1:{}", free_port());
    let _session = listening_session(&endpoint);
    let mut o = options(dir.path(), &endpoint, Duration::from_millis(700));
    o.domain_id = 7;
    let e = play(&o).unwrap_err();
    assert!(matches!(e, Ros2PlayError::NoSubscriber { .. }), "{e}");
    let text = e.to_string();
    assert!(
        text.contains("/event_camera/events") && text.contains("domain 7"),
        "{text}"
    );

    let missing = play(&options(
        &dir.path().join("nope"),
        &endpoint,
        Duration::ZERO,
    ))
    .unwrap_err();
    assert!(missing.to_string().contains("nope"), "{missing}");
}

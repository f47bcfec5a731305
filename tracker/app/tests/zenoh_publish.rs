//! The zenoh sink seen from a separate zenoh session, as a ROS 2 node under rmw_zenoh would see it: loopback only,
//! peer mode, multicast scouting off, ports picked free at run time.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use drivers::timeline::Tick;
use eventtrack6d::publish::ros2::{self, Attachment};
use eventtrack6d::publish::zenoh::{CongestionPolicy, ZenohConfig, ZenohPosePublisher};
use eventtrack6d::publish::{PoseSink, TickPoses};
use nalgebra::{Isometry3, Vector3};
use std::collections::{BTreeSet, HashMap};
use std::net::TcpListener;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};
use tracker::track::{PoseEstimate, TrackingState};
use zenoh::Wait;

/// A TCP port on 127.0.0.1 that nothing listens on right now.
fn free_port() -> u16 {
    let l = TcpListener::bind("127.0.0.1:0").expect("bind an ephemeral port");
    l.local_addr().expect("local addr").port()
}

/// A peer session that listens on `endpoint`, connects nowhere, with multicast scouting off.
fn subscriber_session(endpoint: &str) -> zenoh::Session {
    let mut c = zenoh::Config::default();
    c.insert_json5("mode", "\"peer\"").unwrap();
    c.insert_json5("listen/endpoints", &format!("[\"{endpoint}\"]"))
        .unwrap();
    c.insert_json5("connect/endpoints", "[]").unwrap();
    c.insert_json5("scouting/multicast/enabled", "false")
        .unwrap();
    zenoh::open(c).wait().expect("open the subscriber session")
}

fn pose(object: usize, tick: u64) -> Isometry3<f64> {
    let k = tick as f64;
    Isometry3::new(
        Vector3::new(
            0.1 * object as f64 + 0.01 * k,
            -0.2 + 0.003 * k,
            0.6 + 0.1 * object as f64,
        ),
        Vector3::new(0.3 + 0.05 * k, -1.1 * object as f64, 0.25 + 0.01 * k),
    )
}

fn now_ns() -> i64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .unwrap()
        .as_nanos() as i64
}

/// TF, detections and diagnostics of the ticks published by [`poses_status_and_liveliness_reach_a_separate_session`]:
/// one message of each per tick, on its key, describing every object as its pose sample does.
fn check_tick_outputs(
    sink: &ZenohPosePublisher,
    sub: &zenoh::pubsub::Subscriber<zenoh::handlers::FifoChannelHandler<zenoh::sample::Sample>>,
    objects: &[String],
    t0_us: i64,
    offset_ns: i64,
    n_ticks: u64,
) {
    let [tf_key, det_key, diag_key] = sink.output_key_exprs().map(|k| k.unwrap().to_owned());
    assert_eq!(
        tf_key,
        ros2::typed_key_expr(0, "/tf", &ros2::types::TF_MESSAGE)
    );
    assert_eq!(
        det_key,
        ros2::typed_key_expr(
            0,
            "eventtrack6d/detections",
            &ros2::types::DETECTION3D_ARRAY
        )
    );
    assert_eq!(
        diag_key,
        ros2::typed_key_expr(
            0,
            "eventtrack6d/diagnostics",
            &ros2::types::DIAGNOSTIC_ARRAY
        )
    );
    let mut got: HashMap<String, Vec<Vec<u8>>> = HashMap::new();
    let deadline = Instant::now() + Duration::from_secs(10);
    let outputs = [&tf_key, &det_key, &diag_key];
    while outputs
        .iter()
        .any(|k| got.get(*k).map_or(0, Vec::len) < n_ticks as usize)
    {
        let left = deadline.saturating_duration_since(Instant::now());
        let Some(sample) = sub.recv_timeout(left).unwrap() else {
            panic!("timed out; received {:?}", got.keys().collect::<Vec<_>>());
        };
        let key = sample.key_expr().as_str().to_owned();
        if outputs.contains(&&key) {
            assert!(
                sample.attachment().is_some(),
                "{key} carries the attachment"
            );
            got.entry(key)
                .or_default()
                .push(sample.payload().to_bytes().into_owned());
        }
    }
    let messages = got[&tf_key].iter().zip(&got[&det_key]).zip(&got[&diag_key]);
    for (k, ((tf, det), diag)) in messages.enumerate() {
        let t_us = t0_us + 8_333 * k as i64;
        let stamp = t_us * 1000 + offset_ns;
        let tf = ros2::tf::decode_tf_message(tf).unwrap();
        let det = ros2::vision::decode_detection3d_array(det).unwrap();
        let diag = ros2::diagnostic::decode_diagnostic_array(diag).unwrap();
        assert_eq!(tf.len(), objects.len());
        assert_eq!(det.detections.len(), objects.len());
        assert_eq!(diag.status.len(), objects.len());
        assert_eq!(det.header.stamp.as_nanos(), stamp);
        assert_eq!(diag.header.frame_id, "eventtrack6d_camera");
        for (o, name) in objects.iter().enumerate() {
            let expected = ros2::Pose::from_isometry(&pose(o, k as u64));
            assert_eq!(tf[o].header.stamp.as_nanos(), stamp);
            assert_eq!(tf[o].header.frame_id, "eventtrack6d_camera");
            assert_eq!(&tf[o].child_frame_id, name);
            assert_eq!(tf[o].translation, expected.position);
            assert_eq!(tf[o].rotation_xyzw, expected.orientation_xyzw);
            let d = &det.detections[o];
            assert_eq!(&d.id, name);
            assert_eq!(d.results.len(), 1);
            assert_eq!(&d.results[0].class_id, name);
            assert_eq!(d.results[0].score, f64::from(0.9f32));
            assert_eq!(d.results[0].pose, expected);
            // No mesh given: a zero-sized box at the object's origin.
            assert_eq!(d.bbox_size, [0.0; 3]);
            assert_eq!(d.bbox_center, expected);
            let s = &diag.status[o];
            assert_eq!(s.level, ros2::diagnostic::level::OK);
            assert_eq!(s.name, format!("eventtrack6d: {name}"));
            assert_eq!(s.message, "tracking");
            assert!(
                s.values.contains(&("quality".into(), "0.9".into())),
                "{:?}",
                s.values
            );
            assert!(s.values.contains(&("t_us".into(), t_us.to_string())));
        }
    }
}

#[test]
fn poses_status_and_liveliness_reach_a_separate_session() {
    let endpoint = format!("tcp/127.0.0.1:{}", free_port());
    let sub_session = subscriber_session(&endpoint);
    let poses_sub = sub_session
        .declare_subscriber("0/eventtrack6d/*/pose/**")
        .wait()
        .unwrap();
    let outputs_sub = sub_session.declare_subscriber("0/**").wait().unwrap();
    let status_sub = sub_session
        .declare_subscriber("eventtrack6d/status")
        .wait()
        .unwrap();

    let objects = vec!["mug".to_string(), "drill_2".to_string()];
    // Every sample is counted below. The default policy drops a sample when the transport's queue has no room at
    // once; with other work competing for two cores, samples went missing in two runs of five.
    let config = ZenohConfig {
        connect: vec![endpoint.clone()],
        listen: vec![format!("tcp/127.0.0.1:{}", free_port())],
        congestion_control: CongestionPolicy::Block,
        ..Default::default()
    };
    // ROS time = camera time + 1.7e9 s (a 2023 wall-clock epoch).
    let offset_ns: i64 = 1_700_000_000 * 1_000_000_000;
    let mut sink = ZenohPosePublisher::new(&config, &objects, offset_ns).expect("sink");
    assert_eq!(sink.name(), "zenoh");

    // Wait until the sessions are connected and the subscribers are known: status puts start arriving.
    let deadline = Instant::now() + Duration::from_secs(20);
    loop {
        sink.put_status(br#"{"warmup":true}"#).unwrap();
        if status_sub
            .recv_timeout(Duration::from_millis(100))
            .unwrap()
            .is_some()
        {
            break;
        }
        assert!(
            Instant::now() < deadline,
            "the subscriber session never received a status put"
        );
    }
    // Let the pose subscriber's declaration settle as well (it was declared before the status one).
    std::thread::sleep(Duration::from_millis(200));

    let n_ticks = 5u64;
    let t0_us = 12_345_678i64;
    let before_ns = now_ns();
    for k in 0..n_ticks {
        let tick = Tick {
            index: k,
            t_us: t0_us + 8_333 * k as i64,
            depth_frame: None,
            synthesized: false,
        };
        let estimates: Vec<PoseEstimate> = (0..objects.len())
            .map(|o| PoseEstimate {
                object: o,
                t_us: tick.t_us,
                pose: pose(o, k),
                quality: 0.9,
                state: TrackingState::Tracking,
            })
            .collect();
        let tp = TickPoses {
            tick: &tick,
            estimates: &estimates,
            objects: &objects,
            decoded_at: Instant::now(),
        };
        sink.publish(&tp).expect("publish");
    }
    let after_ns = now_ns();
    assert_eq!(sink.counters().published, n_ticks * 2);
    assert_eq!(sink.counters().failed, 0);

    // Every sample arrives on its rmw_zenoh key with a 33-byte attachment and decodes to the pose.
    let mut by_key: HashMap<String, Vec<(Attachment, ros2::PoseStampedMsg)>> = HashMap::new();
    let deadline = Instant::now() + Duration::from_secs(10);
    while by_key.values().map(Vec::len).sum::<usize>() < (n_ticks as usize) * objects.len() {
        let left = deadline.saturating_duration_since(Instant::now());
        let sample = poses_sub.recv_timeout(left).unwrap().unwrap_or_else(|| {
            panic!(
                "timed out; received {:?}",
                by_key.keys().collect::<Vec<_>>()
            )
        });
        let attachment = sample
            .attachment()
            .expect("every sample carries rmw_zenoh's attachment")
            .to_bytes();
        assert_eq!(attachment.len(), 33);
        assert_eq!(attachment[16], 0x10);
        let attachment = Attachment::from_bytes(&attachment).unwrap();
        let msg = ros2::decode_pose_stamped(&sample.payload().to_bytes()).expect("CDR decodes");
        by_key
            .entry(sample.key_expr().as_str().to_owned())
            .or_default()
            .push((attachment, msg));
    }
    assert!(
        poses_sub
            .recv_timeout(Duration::from_millis(200))
            .unwrap()
            .is_none(),
        "no extra samples"
    );

    for (o, name) in objects.iter().enumerate() {
        let key = ros2::pose_stamped_key_expr(0, &format!("eventtrack6d/{name}/pose"));
        assert_eq!(sink.pose_key_expr(o), Some(key.as_str()));
        assert!(key.ends_with(
            "/geometry_msgs::msg::dds_::PoseStamped_/\
             RIHS01_10f3786d7d40fd2b54367835614bff85d4ad3b5dab62bf8bca0cc232d73b4cd8"
        ));
        let samples = by_key
            .get(&key)
            .unwrap_or_else(|| panic!("nothing on {key}"));
        assert_eq!(samples.len(), n_ticks as usize);
        for (k, (att, msg)) in samples.iter().enumerate() {
            assert_eq!(
                att.sequence_number,
                k as i64 + 1,
                "sequence numbers start at 1 and increase by 1"
            );
            assert_eq!(att.gid, sink.gid(o).unwrap());
            assert!(
                (before_ns - 1_000_000_000..=after_ns + 1_000_000_000)
                    .contains(&att.source_timestamp_ns),
                "source timestamp is the system time of the put"
            );
            assert_eq!(msg.frame_id, "eventtrack6d_camera");
            let t_us = t0_us + 8_333 * k as i64;
            assert_eq!(msg.stamp.as_nanos(), t_us * 1000 + offset_ns);
            let expected = pose(o, k as u64);
            let got = msg.to_isometry();
            assert!((got.translation.vector - expected.translation.vector).amax() < 1e-9);
            let q = expected.rotation.quaternion();
            let [x, y, z, w] = msg.orientation_xyzw;
            // Same quaternion (sign included: the sink does not flip it).
            assert!(
                (x - q.i).abs() < 1e-9
                    && (y - q.j).abs() < 1e-9
                    && (z - q.k).abs() < 1e-9
                    && (w - q.w).abs() < 1e-9
            );
        }
    }
    assert_ne!(sink.gid(0), sink.gid(1), "each publisher has its own GID");
    check_tick_outputs(&sink, &outputs_sub, &objects, t0_us, offset_ns, n_ticks);

    // The liveliness tokens are visible to the other session, as rmw_zenoh's graph cache queries them.
    let expected: BTreeSet<String> = sink
        .liveliness_key_exprs()
        .iter()
        .map(|s| s.to_string())
        .collect();
    assert_eq!(
        expected.len(),
        6,
        "node, 2 poses, TF, detections, diagnostics"
    );
    let zid = sink.zid();
    assert!(expected.contains(&format!("@ros2_lv/0/{zid}/0/0/NN/%/%/eventtrack6d")));
    assert!(expected.contains(&format!(
        "@ros2_lv/0/{zid}/0/3/MP/%/%/eventtrack6d/%tf/tf2_msgs::msg::dds_::TFMessage_/\
         RIHS01_e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087/::,:,:,:,,"
    )));
    assert!(expected.contains(&format!(
        "@ros2_lv/0/{zid}/0/1/MP/%/%/eventtrack6d/%eventtrack6d%mug%pose/geometry_msgs::msg::dds_::PoseStamped_/\
         RIHS01_10f3786d7d40fd2b54367835614bff85d4ad3b5dab62bf8bca0cc232d73b4cd8/::,:,:,:,,"
    )));
    let mut seen = BTreeSet::new();
    let deadline = Instant::now() + Duration::from_secs(10);
    while !expected.is_subset(&seen) && Instant::now() < deadline {
        let replies = sub_session
            .liveliness()
            .get("@ros2_lv/0/**")
            .wait()
            .unwrap();
        while let Ok(reply) = replies.recv() {
            if let Ok(sample) = reply.result() {
                seen.insert(sample.key_expr().as_str().to_owned());
            }
        }
        if !expected.is_subset(&seen) {
            std::thread::sleep(Duration::from_millis(100));
        }
    }
    assert!(
        expected.is_subset(&seen),
        "expected {expected:#?}\nseen {seen:#?}"
    );

    // Status JSON arrives byte for byte.
    let status = br#"{"state":"tracking","objects":[{"name":"mug","quality":0.9}]}"#;
    sink.put_status(status).unwrap();
    let deadline = Instant::now() + Duration::from_secs(5);
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        let sample = status_sub
            .recv_timeout(left)
            .unwrap()
            .expect("status arrives");
        if sample.payload().to_bytes().as_ref() == status.as_slice() {
            assert_eq!(sample.encoding(), &zenoh::bytes::Encoding::APPLICATION_JSON);
            break;
        }
    }
    assert_eq!(sink.status_counters().failed, 0);

    // A pose for an unknown object is counted and reported, and does not stop the others.
    let tick = Tick {
        index: 99,
        t_us: t0_us,
        depth_frame: None,
        synthesized: false,
    };
    let bad = [
        PoseEstimate {
            object: 7,
            t_us: t0_us,
            pose: pose(0, 0),
            quality: 1.0,
            state: TrackingState::Tracking,
        },
        PoseEstimate {
            object: 0,
            t_us: t0_us,
            pose: pose(0, 0),
            quality: 1.0,
            state: TrackingState::Tracking,
        },
    ];
    let err = sink
        .publish(&TickPoses {
            tick: &tick,
            estimates: &bad,
            objects: &objects,
            decoded_at: Instant::now(),
        })
        .unwrap_err();
    assert!(err.to_string().contains("object index 7"), "{err}");
    assert_eq!(sink.counters().failed, 1);
    assert_eq!(sink.counters().published, n_ticks * 2 + 1);

    sink.close().expect("close");
    // After close the tokens are gone from the graph.
    let deadline = Instant::now() + Duration::from_secs(10);
    loop {
        let replies = sub_session
            .liveliness()
            .get(format!("@ros2_lv/0/{zid}/**"))
            .wait()
            .unwrap();
        let mut any = false;
        while let Ok(reply) = replies.recv() {
            any |= reply.result().is_ok();
        }
        if !any {
            break;
        }
        assert!(
            Instant::now() < deadline,
            "liveliness tokens still visible after close"
        );
        std::thread::sleep(Duration::from_millis(100));
    }
}

#[test]
fn starts_quickly_without_a_router() {
    let config = ZenohConfig {
        connect: vec![format!("tcp/127.0.0.1:{}", free_port())],
        listen: vec!["tcp/127.0.0.1:0".into()],
        ..Default::default()
    };
    let start = Instant::now();
    let mut sink =
        ZenohPosePublisher::new(&config, &["mug".to_string()], 0).expect("no router is needed");
    assert!(
        start.elapsed() < Duration::from_secs(3),
        "took {:?}",
        start.elapsed()
    );
    // Publishing with nobody listening succeeds (zenoh routes to no one) and counts the pose.
    let tick = Tick {
        index: 0,
        t_us: 1,
        depth_frame: None,
        synthesized: false,
    };
    let e = [PoseEstimate {
        object: 0,
        t_us: 1,
        pose: Isometry3::identity(),
        quality: 1.0,
        state: TrackingState::Lost,
    }];
    sink.publish(&TickPoses {
        tick: &tick,
        estimates: &e,
        objects: &["mug".into()],
        decoded_at: Instant::now(),
    })
    .unwrap();
    assert_eq!(sink.counters().published, 1);
}

#[test]
fn setup_errors_are_typed() {
    let config = ZenohConfig {
        listen: vec!["tcp/127.0.0.1:0".into()],
        connect: vec![],
        ..Default::default()
    };
    let e = ZenohPosePublisher::new(&config, &["bad name".to_string()], 0)
        .err()
        .expect("rejected");
    assert!(e.to_string().contains("\"bad name\""), "{e}");
    let e = ZenohPosePublisher::new(&config, &["a".to_string(), "a".to_string()], 0)
        .err()
        .expect("rejected");
    assert!(e.to_string().contains("appears twice"), "{e}");
}

/// The replies to `selector` from `session`: Ok(payload) for a pose, Err(message) for a refusal; empty while no
/// queryable matches yet.
fn ask(session: &zenoh::Session, selector: &str) -> Vec<Result<String, String>> {
    let replies = session.get(selector).wait().expect("query sent");
    let mut out = Vec::new();
    while let Ok(reply) = replies.recv() {
        out.push(match reply.result() {
            Ok(sample) => Ok(sample.payload().try_to_string().unwrap().into_owned()),
            Err(e) => Err(e.payload().try_to_string().unwrap().into_owned()),
        });
    }
    out
}

#[test]
fn pose_queries_answer_at_any_time_between_published_ticks() {
    let endpoint = format!("tcp/127.0.0.1:{}", free_port());
    let asker = subscriber_session(&endpoint);
    let config = ZenohConfig {
        connect: vec![endpoint],
        listen: vec![format!("tcp/127.0.0.1:{}", free_port())],
        ..Default::default()
    };
    let objects = vec!["mug".to_string()];
    let offset_ns = 1_000_000_000;
    let mut sink = ZenohPosePublisher::new(&config, &objects, offset_ns).expect("sink");
    let key = sink
        .pose_query_key_expr(0)
        .expect("queries are on by default")
        .to_owned();
    assert_eq!(key, "eventtrack6d/mug/pose_at");
    // Poses at ticks 8333 us apart: x grows 1 cm per tick, no rotation.
    let at = |k: i64| Isometry3::new(Vector3::new(0.01 * k as f64, 0.0, 0.5), Vector3::zeros());
    for k in 0..4i64 {
        let tick = Tick {
            index: k as u64,
            t_us: 100_000 + 8_333 * k,
            depth_frame: None,
            synthesized: false,
        };
        let estimates = [PoseEstimate {
            object: 0,
            t_us: tick.t_us,
            pose: at(k),
            quality: 0.8,
            state: TrackingState::Tracking,
        }];
        sink.publish(&TickPoses {
            tick: &tick,
            estimates: &estimates,
            objects: &objects,
            decoded_at: Instant::now(),
        })
        .expect("publish");
    }
    // Half way between the second and third tick, once the queryable is known to the asker.
    let t_us = 100_000 + 8_333 + 4_166;
    let deadline = Instant::now() + Duration::from_secs(20);
    let replies = loop {
        let replies = ask(&asker, &format!("{key}?t_us={t_us}"));
        if !replies.is_empty() {
            break replies;
        }
        assert!(Instant::now() < deadline, "no queryable answered on {key}");
        std::thread::sleep(Duration::from_millis(100));
    };
    assert_eq!(replies.len(), 1, "{replies:?}");
    let json: serde_json::Value =
        serde_json::from_str(replies[0].as_ref().expect("a pose")).unwrap();
    assert_eq!(json["object"], "mug");
    assert_eq!(json["t_us"], t_us);
    assert_eq!(json["stamp_ns"], t_us * 1000 + offset_ns);
    let x = json["position"][0].as_f64().unwrap();
    assert!(
        (x - 0.01 * (1.0 + 4_166.0 / 8_333.0)).abs() < 1e-9,
        "{json}"
    );
    assert_eq!(json["state"], "tracking");
    assert_eq!(json["revised"], false);
    // The same time as the pose topic's header stamp.
    let by_stamp = ask(
        &asker,
        &format!("{key}?stamp_ns={}", t_us * 1000 + offset_ns),
    );
    assert_eq!(by_stamp, replies);
    // Refusals say why.
    for (parameters, says) in [
        ("", "no time given"),
        ("t_us=soon", "not a whole number"),
        ("t_us=1", "before the oldest pose kept"),
        ("t_us=999999999", "after the latest pose"),
    ] {
        let replies = ask(&asker, &format!("{key}?{parameters}"));
        match replies.as_slice() {
            [Err(m)] => assert!(m.contains(says), "{parameters}: {m}"),
            other => panic!("{parameters}: {other:?}"),
        }
    }
    assert_eq!(sink.pose_query_counts(), (2, 4));
    // The tracker revises the third tick (tracked again from a late depth frame): queries answer with it.
    let third = 100_000 + 2 * 8_333;
    sink.revise(&[PoseEstimate {
        object: 0,
        t_us: third,
        pose: at(5),
        quality: 0.9,
        state: TrackingState::Tracking,
    }]);
    let replies = ask(&asker, &format!("{key}?t_us={third}"));
    let json: serde_json::Value =
        serde_json::from_str(replies[0].as_ref().expect("a pose")).unwrap();
    assert_eq!(json["revised"], true, "{json}");
    assert!(
        (json["position"][0].as_f64().unwrap() - 0.05).abs() < 1e-12,
        "{json}"
    );
    assert_eq!(json["quality"], 0.8, "quality stays as published");
}

#[test]
fn pose_queries_can_be_turned_off() {
    let config = ZenohConfig {
        connect: vec![],
        listen: vec![format!("tcp/127.0.0.1:{}", free_port())],
        pose_queries: false,
        ..Default::default()
    };
    let sink = ZenohPosePublisher::new(&config, &["mug".to_string()], 0).expect("sink");
    assert_eq!(sink.pose_query_key_expr(0), None);
}

/// A set-pose sample and a reset call from another session reach the tracker's side of the control queue; the
/// service's reply carries the outcome the tracker side gives, with the caller's sequence number and GID; a
/// set-pose that cannot be used is refused before it reaches the tracker, and the diagnostics say so.
#[test]
fn set_pose_and_reset_reach_the_tracker_and_are_answered() {
    use eventtrack6d::publish::control::{ControlCommand, ControlOutcome, control_channel};
    use eventtrack6d::publish::zenoh::ObjectOutput;
    let endpoint = format!("tcp/127.0.0.1:{}", free_port());
    let other = subscriber_session(&endpoint);
    let config = ZenohConfig {
        connect: vec![endpoint.clone()],
        listen: vec![format!("tcp/127.0.0.1:{}", free_port())],
        congestion_control: CongestionPolicy::Block,
        ..Default::default()
    };
    let (sender, inbox) = control_channel();
    let mut mug = ObjectOutput::named("mug");
    mug.bounds = ([-0.04, -0.05, 0.0], [0.04, 0.05, 0.1]);
    let mut sink = ZenohPosePublisher::with_outputs(&config, &[mug], 0, Some(sender)).unwrap();
    let zid = sink.zid();
    let tokens: BTreeSet<String> = sink
        .liveliness_key_exprs()
        .iter()
        .map(|s| s.to_string())
        .collect();
    assert!(tokens.contains(&format!(
        "@ros2_lv/0/{zid}/0/5/MS/%/%/eventtrack6d/%eventtrack6d%mug%set_pose/geometry_msgs::msg::dds_::PoseStamped_/\
         RIHS01_10f3786d7d40fd2b54367835614bff85d4ad3b5dab62bf8bca0cc232d73b4cd8/::,:,:,:,,"
    )), "{tokens:#?}");
    assert!(tokens.contains(&format!(
        "@ros2_lv/0/{zid}/0/6/SS/%/%/eventtrack6d/%eventtrack6d%reset/std_srvs::srv::dds_::Trigger_/\
         RIHS01_eeff2cd6fa5ad9d27cdf4dec64818317839b62f212a91e6b5304b634b2062c5f/::,:,:,:,,"
    )), "{tokens:#?}");
    let set_key = ros2::typed_key_expr(0, "eventtrack6d/mug/set_pose", &ros2::types::POSE_STAMPED);
    let publisher = other.declare_publisher(set_key).wait().unwrap();
    let mut payload = Vec::new();
    let wrong_frame = |out: &mut Vec<u8>| {
        ros2::encode_pose_stamped(
            out,
            ros2::RosTime::default(),
            "world",
            [0.0, 0.0, 0.5],
            [0.0, 0.0, 0.0, 1.0],
        )
    };
    // Connected once the other session sees the subscription's token; the declaration itself came before it.
    let deadline = Instant::now() + Duration::from_secs(20);
    while other
        .liveliness()
        .get(format!("@ros2_lv/0/{zid}/**"))
        .wait()
        .unwrap()
        .recv_timeout(Duration::from_millis(200))
        .ok()
        .flatten()
        .is_none()
    {
        assert!(Instant::now() < deadline, "the sessions never connected");
    }
    std::thread::sleep(Duration::from_millis(200));
    let diag_sub = other
        .declare_subscriber("0/eventtrack6d/diagnostics/**")
        .wait()
        .unwrap();
    wrong_frame(&mut payload);
    publisher.put(payload.clone()).wait().unwrap();
    std::thread::sleep(Duration::from_millis(300));
    let tick = Tick {
        index: 0,
        t_us: 1000,
        depth_frame: None,
        synthesized: false,
    };
    let est = [PoseEstimate {
        object: 0,
        t_us: 1000,
        pose: pose(0, 0),
        quality: 0.5,
        state: TrackingState::Degraded,
    }];
    let names = ["mug".to_string()];
    let deadline = Instant::now() + Duration::from_secs(10);
    let diag = loop {
        sink.publish(&TickPoses {
            tick: &tick,
            estimates: &est,
            objects: &names,
            decoded_at: Instant::now(),
        })
        .unwrap();
        if let Some(sample) = diag_sub.recv_timeout(Duration::from_millis(100)).unwrap() {
            break ros2::diagnostic::decode_diagnostic_array(&sample.payload().to_bytes()).unwrap();
        }
        assert!(Instant::now() < deadline, "no diagnostics arrived");
    };
    let status = &diag.status[0];
    assert_eq!(status.level, ros2::diagnostic::level::WARN);
    assert_eq!(status.message, "degraded");
    let last = status
        .values
        .iter()
        .find(|(k, _)| k == "last_control")
        .expect("last_control");
    assert!(
        last.1.starts_with("refused: mug: frame_id \"world\""),
        "{last:?}"
    );
    assert!(
        inbox.try_next().is_none(),
        "a pose in another frame never reaches the tracker"
    );

    ros2::encode_pose_stamped(
        &mut payload,
        ros2::RosTime { sec: 1, nanosec: 5 },
        "",
        [0.1, 0.2, 0.5],
        [0.0, 0.0, 0.0, 1.0],
    );
    publisher.put(payload.clone()).wait().unwrap();
    let deadline = Instant::now() + Duration::from_secs(10);
    let request = loop {
        if let Some(r) = inbox.try_next() {
            break r;
        }
        assert!(Instant::now() < deadline, "the set-pose never arrived");
        std::thread::sleep(Duration::from_millis(10));
    };
    match &request.command {
        ControlCommand::SetPose {
            object,
            stamp_ns,
            pose,
        } => {
            assert_eq!((*object, *stamp_ns), (0, 1_000_000_005));
            assert!((pose.translation.vector - Vector3::new(0.1, 0.2, 0.5)).amax() < 1e-12);
        }
        other => panic!("{other:?}"),
    }
    (request.reply)(ControlOutcome::done("mug re-seeded"));

    // The reset service, called as rmw_zenoh's clients call: a query with the CDR request and an attachment.
    let service_key = ros2::typed_key_expr(0, "eventtrack6d/reset", &ros2::types::TRIGGER);
    let mut req = Vec::new();
    ros2::trigger::encode_trigger_request(&mut req);
    let client_gid = [7u8; 16];
    let attachment = Attachment {
        sequence_number: 41,
        source_timestamp_ns: now_ns(),
        gid: client_gid,
    };
    let replies = other
        .get(service_key)
        .payload(req)
        .attachment(attachment.to_bytes())
        .timeout(Duration::from_secs(10))
        .wait()
        .unwrap();
    let deadline = Instant::now() + Duration::from_secs(10);
    let request = loop {
        if let Some(r) = inbox.try_next() {
            break r;
        }
        assert!(Instant::now() < deadline, "the reset never arrived");
        std::thread::sleep(Duration::from_millis(10));
    };
    assert_eq!(request.command, ControlCommand::Reset);
    (request.reply)(ControlOutcome::refused("no tick yet"));
    let reply = replies.recv().unwrap().into_result().unwrap();
    let response = ros2::trigger::decode_trigger_response(&reply.payload().to_bytes()).unwrap();
    assert!(!response.success);
    assert_eq!(response.message, "no tick yet");
    let att = Attachment::from_bytes(&reply.attachment().unwrap().to_bytes()).unwrap();
    assert_eq!((att.sequence_number, att.gid), (41, client_gid));
    sink.close().unwrap();
}

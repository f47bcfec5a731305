//! The zenoh sink's per-tick ROS 2 outputs beside the poses (`tf2_msgs/msg/TFMessage` on `/tf`,
//! `vision_msgs/msg/Detection3DArray` on `eventtrack6d/detections`, `diagnostic_msgs/msg/DiagnosticArray` on
//! `eventtrack6d/diagnostics`), end to end: a generated two-object recording (the mug and a can) is replayed through
//! `eventtrack6d::runtime::run` with the CSV and zenoh sinks on, a separate zenoh session collects every sample of
//! the three topics, and the independent ROS 2 type system (rosbags, `tests/ros2/rosbags_check.py`; not the
//! project's own decoder) decodes them. The can starts out of view (configured first pose 1 m to the side), so it is
//! lost until re-detection finds it and TF must leave it out meanwhile. Every field of every message is then checked against the CSV sink's row of
//! the same tick: stamps, frame ids, TF children (the configured child frame mapping, lost objects absent), poses
//! to the bit (the CSV prints shortest round-trip numbers), detection ids, class ids and scores (the quality, f32
//! widened), the bounding box from the mesh's axis-aligned box, and the diagnostics' levels, messages and values.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use eventtrack6d::publish::ros2::{self, Attachment, types};
use eventtrack6d::runtime;
use eventtrack6d_tests::rosbags::{assert_fields_within, rosbags_decode};
use eventtrack6d_tests::tick_fixture::mug_and_can_recording;
use eventtrack6d_tests::zenoh_run::{HeldRun, free_port, peer_session};
use nalgebra::{Isometry3, Point3, Quaternion, Translation3, UnitQuaternion};
use scene::mesh::{MeshLoadOptions, load_obj};
use serde_json::{Value, json};
use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tracker::recording::{POSE_CSV_HEADER, PoseTrack, recording_ticks};
use zenoh::Wait;

const FRAME_ID: &str = "eventtrack6d_camera";
const NODE: &str = "eventtrack6d";
/// The object whose TF child frame the configuration renames, and the name it gets.
const MAPPED: (&str, &str) = ("can", "can_link");
/// How far from its true first pose the can starts, metres (camera frame): out of view.
const LOST_OFFSET_M: [f64; 3] = [1.0, 0.0, 0.0];

/// One sample as it arrived: key, payload, attachment.
type Sample = (String, Vec<u8>, Option<Vec<u8>>);

/// One CSV row, its numbers kept as the text the sink wrote (shortest round-trip forms) and parsed exactly.
#[derive(Debug, Clone)]
struct CsvRow {
    t_us: i64,
    object: String,
    /// x, y, z, qx, qy, qz, qw.
    numbers: [f64; 7],
    /// The quality as written (Rust's `f32` Display).
    quality_text: String,
    quality: f32,
    state: String,
}

impl CsvRow {
    fn parse(line: &str) -> Self {
        let f: Vec<&str> = line.split(',').collect();
        assert_eq!(f.len(), 11, "{line}");
        Self {
            t_us: f[0].parse().unwrap(),
            object: f[1].to_owned(),
            numbers: std::array::from_fn(|k| f[k + 2].parse().unwrap()),
            quality_text: f[9].to_owned(),
            quality: f[9].parse().unwrap(),
            state: f[10].to_owned(),
        }
    }

    /// The pose, bit for bit the one the tracker held (the quaternion as stored, not renormalised).
    fn pose(&self) -> Isometry3<f64> {
        let [x, y, z, qx, qy, qz, qw] = self.numbers;
        Isometry3::from_parts(
            Translation3::new(x, y, z),
            UnitQuaternion::new_unchecked(Quaternion::new(qw, qx, qy, qz)),
        )
    }
}

// --- expected messages, in rosbags_check.py's JSON form ----------------------------------------------------------

fn header_json(t_us: i64) -> Value {
    let ns = t_us * 1000;
    json!({
        "stamp": {"sec": ns.div_euclid(1_000_000_000), "nanosec": ns.rem_euclid(1_000_000_000)},
        "frame_id": FRAME_ID,
    })
}

fn position_json(p: [f64; 3]) -> Value {
    json!({"x": p[0], "y": p[1], "z": p[2]})
}

fn quaternion_json(r: &CsvRow) -> Value {
    let n = r.numbers;
    json!({"x": n[3], "y": n[4], "z": n[5], "w": n[6]})
}

fn pose_json(r: &CsvRow) -> Value {
    let n = r.numbers;
    json!({"position": position_json([n[0], n[1], n[2]]), "orientation": quaternion_json(r)})
}

fn child_frame(object: &str) -> String {
    if object == MAPPED.0 {
        MAPPED.1.to_owned()
    } else {
        object.to_owned()
    }
}

/// The TF message of a tick: one transform per object that is not lost, camera frame to the object's child frame.
fn tf_json(rows: &[CsvRow]) -> Value {
    let transforms: Vec<Value> = rows
        .iter()
        .filter(|r| r.state != "lost")
        .map(|r| {
            let n = r.numbers;
            json!({
                "header": header_json(r.t_us),
                "child_frame_id": child_frame(&r.object),
                "transform": {
                    "translation": position_json([n[0], n[1], n[2]]),
                    "rotation": quaternion_json(r),
                },
            })
        })
        .collect();
    json!({ "transforms": transforms })
}

/// The detections of a tick: one per object in object order, the quality as the score, the box the mesh's
/// axis-aligned bounding box (its centre moved by the pose, the pose's orientation, its extents).
fn detections_json(
    t_us: i64,
    rows: &[CsvRow],
    boxes: &BTreeMap<String, scene::mesh::Aabb>,
) -> Value {
    let detections: Vec<Value> = rows
        .iter()
        .map(|r| {
            let b = &boxes[&r.object];
            let centre = r.pose() * Point3::from((b.min.coords + b.max.coords) * 0.5);
            let size = b.max - b.min;
            json!({
                "header": header_json(r.t_us),
                "results": [{
                    "hypothesis": {"class_id": r.object, "score": f64::from(r.quality)},
                    "pose": {"pose": pose_json(r), "covariance": vec![0.0f64; 36]},
                }],
                "bbox": {
                    "center": {"position": position_json([centre.x, centre.y, centre.z]), "orientation": quaternion_json(r)},
                    "size": position_json([size.x, size.y, size.z]),
                },
                "id": r.object,
            })
        })
        .collect();
    json!({"header": header_json(t_us), "detections": detections})
}

/// The tracking state of a tick: one status per object (no control command was sent, so no `last_control`).
fn diagnostics_json(t_us: i64, rows: &[CsvRow]) -> Value {
    let status: Vec<Value> = rows
        .iter()
        .map(|r| {
            let level = match r.state.as_str() {
                "tracking" => 0,
                "degraded" => 1,
                "lost" => 2,
                other => panic!("CSV state {other}"),
            };
            json!({
                "level": level,
                "name": format!("{NODE}: {}", r.object),
                "message": r.state,
                "hardware_id": FRAME_ID,
                "values": [
                    {"key": "object", "value": r.object},
                    {"key": "state", "value": r.state},
                    {"key": "quality", "value": r.quality_text},
                    {"key": "t_us", "value": r.t_us.to_string()},
                ],
            })
        })
        .collect();
    json!({"header": header_json(t_us), "status": status})
}

/// The box centre is computed by the sink (pose applied to the mesh box's centre) and again here: equal to
/// rounding, not to the bit.
fn box_centre_tolerance(path: &str) -> Option<f64> {
    path.contains(".bbox.center.position.").then_some(1e-12)
}

#[test]
fn tf_detections_and_diagnostics_read_by_rosbags_match_the_csv_sink_tick_by_tick() {
    let started = Instant::now();
    let dir = tempfile::tempdir().unwrap();
    let rec_dir = dir.path().join("rec");
    let rec = mug_and_can_recording(&rec_dir);
    let ticks = recording_ticks(&rec).unwrap();
    let generated = started.elapsed();

    // The objects and their first poses: the mug at its true pose, the can 1 m to the side of its own (out of
    // view), so that the can's estimate is lost until re-detection finds it, and TF must leave it out meanwhile.
    let gt = rec.ground_truth.clone().unwrap();
    let mut objects_toml = String::new();
    for (name, offset) in [("mug", [0.0; 3]), (MAPPED.0, LOST_OFFSET_M)] {
        let pose = PoseTrack::from_samples(&gt, name)
            .interpolated_at(ticks[0].t_us)
            .unwrap();
        let t = pose.translation.vector;
        let q = pose.rotation.coords;
        objects_toml += &format!(
            "[[objects]]\nname = \"{name}\"\nmesh = \"{}\"\nposition = [{:?}, {:?}, {:?}]\n\
             orientation = [{:?}, {:?}, {:?}, {:?}]\n",
            rec.mesh_path(name).display(),
            t.x + offset[0],
            t.y + offset[1],
            t.z + offset[2],
            q.x,
            q.y,
            q.z,
            q.w
        );
    }

    let port = free_port();
    let out_dir = dir.path().join("out");
    // Paced as fast as the tracker goes: the subscriber is connected before the start (the hook below) and the
    // publishers block rather than drop (congestion_control = "block"), so every sample arrives.
    let toml = format!(
        r#"
[source]
kind = "replay"
pace = "fast"
[replay]
recording = "{}"
[tracker]
method = "eventtrack6d"
# Out of view, the can is lost after 4 ticks (12 by default: re-detection found it at the depth frame of tick 11,
# just before it would have been lost, and TF would never have left an object out).
[tracker.parameters.quality]
lost_after_ticks = 4
[output]
dir = "{}"
[status]
period_ms = 50
[sinks]
csv = true
zenoh = true
[zenoh]
listen = ["tcp/127.0.0.1:{port}"]
connect = []
congestion_control = "block"
tf_child_frames = {{ {} = "{}" }}
{objects_toml}"#,
        rec_dir.display(),
        out_dir.display(),
        MAPPED.0,
        MAPPED.1,
    );
    let config = runtime::config::from_toml(&toml, "ros2_outputs.toml").unwrap();

    // The run's sinks come up; its source waits until this test's session is connected.
    let run = HeldRun::start(config);

    let session = peer_session(&format!("tcp/127.0.0.1:{port}"));
    // The keys as rmw_zenoh spells them (docs/zenoh-ros2.md): domain 0, topic without its leading '/', the type.
    let keys = [
        ros2::typed_key_expr(0, "/tf", &types::TF_MESSAGE),
        ros2::typed_key_expr(0, "eventtrack6d/detections", &types::DETECTION3D_ARRAY),
        ros2::typed_key_expr(0, "eventtrack6d/diagnostics", &types::DIAGNOSTIC_ARRAY),
    ];
    let received: [Arc<Mutex<Vec<Sample>>>; 3] = std::array::from_fn(|_| Arc::default());
    let _subscribers: Vec<_> = keys
        .iter()
        .zip(&received)
        .map(|(key, into)| {
            let into = into.clone();
            session
                .declare_subscriber(key.clone())
                .callback(move |s| {
                    into.lock().unwrap().push((
                        s.key_expr().as_str().to_owned(),
                        s.payload().to_bytes().into_owned(),
                        s.attachment().map(|a| a.to_bytes().into_owned()),
                    ));
                })
                .wait()
                .unwrap()
        })
        .collect();
    run.release_when_connected(&session, "eventtrack6d/status");

    let summary = run.join().expect("the run failed");
    // The last samples may still be on their way.
    let deadline = Instant::now() + Duration::from_secs(5);
    while received
        .iter()
        .any(|r| r.lock().unwrap().len() < ticks.len())
        && Instant::now() < deadline
    {
        std::thread::sleep(Duration::from_millis(20));
    }
    std::thread::sleep(Duration::from_millis(100));
    let run_time = started.elapsed() - generated;

    assert_eq!(summary.ticks, ticks.len() as u64, "{summary}");
    for s in &summary.sinks {
        assert_eq!(s.counters.failed + s.counters.dropped, 0, "{}", s.name);
    }
    let objects = summary.objects.clone();
    assert_eq!(objects.len(), 2, "{objects:?}");
    assert!(objects.iter().any(|o| o == MAPPED.0), "{objects:?}");

    // The CSV sink's rows, one per object per tick, in object order.
    let csv = std::fs::read_to_string(summary.outputs.csv.clone().unwrap()).unwrap();
    let mut lines = csv.lines().filter(|l| !l.trim().is_empty());
    assert_eq!(lines.next(), Some(POSE_CSV_HEADER));
    let rows: Vec<CsvRow> = lines.map(CsvRow::parse).collect();
    assert_eq!(rows.len(), ticks.len() * objects.len());
    let per_tick: Vec<&[CsvRow]> = rows.chunks(objects.len()).collect();
    for (tick, rows) in ticks.iter().zip(&per_tick) {
        for (r, name) in rows.iter().zip(&objects) {
            assert_eq!((r.t_us, &r.object), (tick.t_us, name));
        }
    }

    // The meshes' axis-aligned boxes, as the recording ships them.
    let boxes: BTreeMap<String, scene::mesh::Aabb> = objects
        .iter()
        .map(|o| {
            let mesh = load_obj(&rec.mesh_path(o), &MeshLoadOptions::default()).unwrap();
            (o.clone(), mesh.mesh.aabb())
        })
        .collect();

    // One sample per tick on each topic, on its key, numbered from 1 by its publisher (rmw_zenoh's attachment).
    let types = [
        types::TF_MESSAGE.name,
        types::DETECTION3D_ARRAY.name,
        types::DIAGNOSTIC_ARRAY.name,
    ];
    let mut decoded = Vec::new();
    for ((key, samples), ty) in keys.iter().zip(&received).zip(types) {
        let samples = samples.lock().unwrap().clone();
        assert_eq!(samples.len(), ticks.len(), "{ty} samples, one per tick");
        for (i, (k, _, attachment)) in samples.iter().enumerate() {
            assert_eq!(k, key);
            let a = Attachment::from_bytes(attachment.as_deref().expect("an attachment")).unwrap();
            assert_eq!(a.sequence_number, i as i64 + 1, "{ty}");
        }
        let payloads: Vec<Vec<u8>> = samples.into_iter().map(|(_, p, _)| p).collect();
        // The independent decoder, not ours.
        decoded.push(rosbags_decode(ty, &payloads));
    }

    let mut lost = 0;
    let mut states = BTreeMap::<String, usize>::new();
    for (i, (tick, rows)) in ticks.iter().zip(&per_tick).enumerate() {
        let t = tick.t_us;
        assert_fields_within(
            &decoded[0][i],
            &tf_json(rows),
            &format!("tick {i} TF"),
            &box_centre_tolerance,
        );
        assert_fields_within(
            &decoded[1][i],
            &detections_json(t, rows, &boxes),
            &format!("tick {i} detections"),
            &box_centre_tolerance,
        );
        assert_fields_within(
            &decoded[2][i],
            &diagnostics_json(t, rows),
            &format!("tick {i} diagnostics"),
            &box_centre_tolerance,
        );
        lost += rows.iter().filter(|r| r.state == "lost").count();
        for r in rows.iter() {
            *states.entry(r.state.clone()).or_default() += 1;
        }
    }
    // The expected messages above follow the CSV, including its lost objects; these say what the run exercised.
    eprintln!(
        "{} ticks x {} objects: states {states:?} ({lost} lost rows left out of TF); generating {:.1} s, run and \
         checks {:.1} s",
        ticks.len(),
        objects.len(),
        generated.as_secs_f64(),
        run_time.as_secs_f64()
    );
    // The run exercised what the expectations describe: the can was lost while it stood out of view (and left out
    // of TF), and TF named both child frames, the mapped one and the other object's own name.
    assert!(lost > 0, "no lost estimate: {states:?}");
    let children: Vec<&str> = decoded[0]
        .iter()
        .flat_map(|m| m["transforms"].as_array().unwrap())
        .map(|t| t["child_frame_id"].as_str().unwrap())
        .collect();
    assert_eq!(
        children.len(),
        rows.len() - lost,
        "one transform per estimate that is not lost"
    );
    for child in [MAPPED.1, "mug"] {
        assert!(children.contains(&child), "no transform to {child}");
    }
    assert!(!children.contains(&MAPPED.0), "the can's frame is renamed");
}

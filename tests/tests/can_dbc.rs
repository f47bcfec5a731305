//! The shipped DBC (`config/can/eventtrack6d.dbc`) read by an independent parser (`can-dbc`) decodes the tracker's
//! CAN frames (written through the candump sink) to the published poses within the DBC's resolution.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use drivers::timeline::Tick;
use eventtrack6d::publish::can::{CandumpClock, CandumpSink, PoseEncoder};
use eventtrack6d::publish::{PoseSink, TickPoses};
use eventtrack6d_tests::dbc::{DbcDecoder, DbcPose, DbcPoseReader, parse_candump_line};
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};
use std::path::Path;
use std::time::Instant;
use tracker::track::{PoseEstimate, TrackingState};

fn dbc() -> DbcDecoder {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../config/can/eventtrack6d.dbc");
    DbcDecoder::from_file(&path).expect("shipped DBC parses")
}

/// Deterministic pseudo-random poses covering the classic range (+-80 m) and every object slot.
fn poses(ticks: u64, objects: usize) -> Vec<(Tick, Vec<PoseEstimate>)> {
    let mut s: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut next = move || {
        s = s
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((s >> 11) as f64) / ((1u64 << 53) as f64) * 2.0 - 1.0
    };
    (0..ticks)
        .map(|i| {
            let tick = Tick {
                index: 250 + i,
                t_us: 4_294_000_000 + i as i64 * 8333,
                depth_frame: None,
                synthesized: false,
            };
            let ests = (0..objects)
                .map(|object| {
                    let scale = if i % 3 == 0 { 80.0 } else { 2.0 };
                    let t = Translation3::new(next() * scale, next() * scale, next() * scale);
                    let q = Quaternion::new(next(), next(), next(), next());
                    PoseEstimate {
                        object,
                        t_us: tick.t_us + object as i64,
                        pose: Isometry3::from_parts(t, UnitQuaternion::from_quaternion(q)),
                        quality: (next() * 0.5 + 0.5) as f32,
                        state: [
                            TrackingState::Tracking,
                            TrackingState::Degraded,
                            TrackingState::Lost,
                        ][(i as usize + object) % 3],
                    }
                })
                .collect();
            (tick, ests)
        })
        .collect()
}

fn check(est: &PoseEstimate, got: &DbcPose, pos_res: f64, quat_res: f64, quality_res: f64) {
    let t = est.pose.translation.vector;
    for (i, v) in [t.x, t.y, t.z].iter().enumerate() {
        assert!(
            (got.position[i] - v).abs() <= pos_res / 2.0 + 1e-9,
            "object {} position {i}",
            est.object
        );
    }
    let q = est.pose.rotation.quaternion();
    let sign = if q.w < 0.0 { -1.0 } else { 1.0 };
    for (i, v) in [q.i, q.j, q.k, q.w].iter().enumerate() {
        // Half a step of rounding; a component of exactly 1 is clamped one step below (classic).
        assert!(
            (got.quaternion[i] - sign * v).abs() <= quat_res * 1.01,
            "object {} quaternion {i}",
            est.object
        );
    }
    assert!((got.quality - f64::from(est.quality)).abs() <= quality_res / 2.0 + 1e-6);
    assert_eq!(got.state, est.state.code());
    assert_eq!(got.t_us_low32, est.t_us as u32);
}

fn run(fd: bool) {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("can.log");
    let objects = 16;
    let data = poses(30, objects);
    let names: Vec<String> = (0..objects).map(|i| format!("obj{i}")).collect();
    let mut sink = CandumpSink::create(&log, "can0", PoseEncoder { base_id: 0x300, fd })
        .unwrap()
        .with_clock(CandumpClock::Camera);
    for (tick, ests) in &data {
        let tp = TickPoses {
            tick,
            estimates: ests,
            objects: &names,
            decoded_at: Instant::now(),
        };
        sink.publish(&tp).unwrap();
    }
    sink.flush().unwrap();

    let decoder = dbc();
    let spec = |name: &str, sig: &str| {
        decoder
            .messages()
            .values()
            .find(|m| m.name == name)
            .and_then(|m| m.signals.iter().find(|s| s.name == sig))
            .unwrap_or_else(|| panic!("{name}.{sig} in DBC"))
            .factor
    };
    let (pos_res, quat_res, quality_res) = if fd {
        (
            spec("ET6D_O0_PoseFD", "PosX"),
            spec("ET6D_O0_PoseFD", "QuatW"),
            spec("ET6D_O0_PoseFD", "Quality"),
        )
    } else {
        (
            spec("ET6D_O0_PosXY", "PosX"),
            spec("ET6D_O0_QuatWTime", "QuatW"),
            spec("ET6D_O0_PosZStatus", "Quality"),
        )
    };
    let mut reader = DbcPoseReader::new(decoder);
    let mut got = Vec::new();
    for line in std::fs::read_to_string(&log).unwrap().lines() {
        let (id, is_fd, bytes) =
            parse_candump_line(line).unwrap_or_else(|| panic!("bad candump line {line}"));
        if let Some(p) = reader.push(id, is_fd, &bytes).unwrap() {
            got.push(p);
        }
    }
    assert_eq!((reader.bad_crc, reader.discarded), (0, 0));
    assert_eq!(got.len(), data.len() * objects);
    for ((tick, ests), chunk) in data.iter().zip(got.chunks(objects)) {
        for (est, p) in ests.iter().zip(chunk) {
            assert_eq!(p.object, est.object);
            assert_eq!(p.counter, tick.index as u8);
            if fd {
                assert_eq!(p.t_us, Some(est.t_us));
            }
            check(est, p, pos_res, quat_res, quality_res);
        }
    }
}

#[test]
fn dbc_describes_the_layout() {
    let d = dbc();
    assert_eq!(d.messages().len(), 16 * 4 + 16);
    let fd = d.message(0x340).unwrap();
    assert!(fd.fd && fd.size == 48 && fd.name == "ET6D_O0_PoseFD");
    let c = d.message(0x300).unwrap();
    assert!(!c.fd && c.size == 8);
    assert!(d.messages().values().all(|m| m.fd == (m.size == 48)));
    let x = c.signals.iter().find(|s| s.name == "PosX").unwrap();
    assert!(x.little_endian && x.signed && x.size == 24 && x.factor == 1e-5 && x.unit == "m");
}

#[test]
fn classic_frames_decode_through_the_dbc() {
    run(false);
}

#[test]
fn fd_frames_decode_through_the_dbc() {
    run(true);
}

#[test]
fn dbc_reader_rejects_corrupt_and_mixed_frames() {
    let mut reader = DbcPoseReader::new(dbc());
    // Frame 0 of object 0, counter 1, with a wrong CRC byte: not used.
    let mut f0 = vec![0u8, 1, 0, 0, 0, 0, 0, 0];
    f0[0] = eventtrack6d_tests::dbc::crc8_autosar(&[0x00, 0x03, 1, 0, 0, 0, 0, 0, 0]) ^ 0x55;
    assert_eq!(reader.push(0x300, false, &f0).unwrap(), None);
    assert_eq!(reader.bad_crc, 1);
    // Big-endian extraction, checked by hand: Motorola signal start 7 (MSB of byte 0), 12 bits over 0xAB 0xC0 = 0xABC.
    let s = eventtrack6d_tests::dbc::SignalSpec {
        name: "m".into(),
        start_bit: 7,
        size: 12,
        little_endian: false,
        signed: false,
        factor: 1.0,
        offset: 0.0,
        unit: String::new(),
    };
    assert_eq!(s.raw(&[0xAB, 0xC0]), Some(0xABC));
}

/// The end-to-end helper on the real file sinks: the same ticks through the CSV sink and the candump sink, then the
/// log decoded through the DBC matches the CSV.
#[test]
fn candump_log_matches_pose_csv_through_the_dbc() {
    for fd in [false, true] {
        let dir = tempfile::tempdir().unwrap();
        let (log, csv) = (dir.path().join("can.log"), dir.path().join("poses.csv"));
        let objects = 3;
        let names: Vec<String> = (0..objects).map(|i| format!("obj{i}")).collect();
        let mut can =
            CandumpSink::create(&log, "can0", PoseEncoder { base_id: 0x300, fd }).unwrap();
        let mut csv_sink = eventtrack6d::publish::csv::CsvPoseSink::create(&csv).unwrap();
        let data = poses(40, objects);
        for (tick, ests) in &data {
            let tp = TickPoses {
                tick,
                estimates: ests,
                objects: &names,
                decoded_at: Instant::now(),
            };
            can.publish(&tp).unwrap();
            csv_sink.publish(&tp).unwrap();
        }
        can.flush().unwrap();
        csv_sink.flush().unwrap();
        let dbc = Path::new(env!("CARGO_MANIFEST_DIR")).join("../config/can/eventtrack6d.dbc");
        let m =
            eventtrack6d_tests::dbc::check_candump_against_csv(&dbc, &log, &csv, &names).unwrap();
        assert_eq!((m.can_poses, m.csv_rows, m.matched), (120, 120, 120));
        assert!(
            m.max_position_error > 0.0,
            "fixed point should differ from f64 somewhere"
        );

        // A corrupted CSV value beyond the resolution is caught.
        let text = std::fs::read_to_string(&csv).unwrap();
        let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
        let mut f: Vec<String> = lines[5].split(',').map(str::to_string).collect();
        let x: f64 = f[2].parse().unwrap();
        f[2] = (x + 1e-4).to_string();
        lines[5] = f.join(",");
        std::fs::write(&csv, lines.join("\n")).unwrap();
        let err = eventtrack6d_tests::dbc::check_candump_against_csv(&dbc, &log, &csv, &names)
            .unwrap_err();
        assert!(err.contains("position 0"), "{err}");
    }
}

//! Recording directories: write, reopen, and refuse inconsistent ones with a message naming the file.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use drivers::event::{CdEvent, EventBuffer, TriggerEdge};
use drivers::recording::{
    CameraIntrinsics, CameraRig, ModelInfo, PoseSample, Recording, RecordingMeta, RecordingWriter,
    TriggerSchedule,
};
use std::path::Path;

fn rig() -> CameraRig {
    let cam = |w, h| CameraIntrinsics {
        width: w,
        height: h,
        fx: 100.0,
        fy: 100.0,
        cx: w as f64 / 2.0,
        cy: h as f64 / 2.0,
        distortion: vec![],
    };
    CameraRig {
        event_camera: cam(64, 48),
        depth_camera: cam(32, 24),
        t_event_depth: [
            [1.0, 0.0, 0.0, 0.05],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
            [0.0, 0.0, 0.0, 1.0],
        ],
        depth_scale_m: 0.001,
    }
}

fn model() -> ModelInfo {
    ModelInfo {
        name: "can".into(),
        diameter_m: 0.15,
        min_m: [-0.03, -0.03, -0.06],
        size_m: [0.06, 0.06, 0.12],
        symmetries_discrete: vec![],
        symmetries_continuous: vec![drivers::recording::ContinuousSymmetry {
            axis: [0.0, 0.0, 1.0],
            offset_m: [0.0, 0.0, 0.0],
        }],
    }
}

fn pose(t: i64) -> PoseSample {
    PoseSample {
        t_us: t,
        object: "can".into(),
        translation: [0.0, 0.0, 0.5],
        rotation_xyzw: [0.0, 0.0, 0.0, 1.0],
    }
}

fn write_sample(dir: &Path) -> (Vec<CdEvent>, Vec<TriggerEdge>) {
    let mut w = RecordingWriter::create(dir, rig(), "test").unwrap();
    let cd: Vec<CdEvent> = (0..100)
        .map(|i| CdEvent {
            t_us: i * 10,
            x: (i % 64) as u16,
            y: 3,
            polarity: i % 2 == 0,
        })
        .collect();
    let tr = vec![
        TriggerEdge {
            t_us: 0,
            channel: 0,
            rising: true,
        },
        TriggerEdge {
            t_us: 200,
            channel: 0,
            rising: false,
        },
    ];
    w.write_events(&cd, &tr).unwrap();
    for n in [0u64, 1, 3] {
        w.write_depth_mm(n, &vec![500 + n as u16; 32 * 24]).unwrap();
    }
    std::fs::write(
        w.models_dir().join("can.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    )
    .unwrap();
    let meta = RecordingMeta {
        generator: "test".into(),
        trigger: TriggerSchedule::default(),
        parameters: Default::default(),
    };
    w.finish(&meta, &[model()], Some(&[pose(0), pose(8333)]))
        .unwrap();
    (cd, tr)
}

#[test]
fn written_recording_reopens_identically() {
    let tmp = tempfile::tempdir().unwrap();
    let (cd, tr) = write_sample(tmp.path());
    let rec = Recording::open(tmp.path()).unwrap();
    assert_eq!(rec.rig, rig());
    assert_eq!(rec.depth_frames, vec![0, 1, 3]);
    assert_eq!(rec.dropped_depth_frames(), vec![2]);
    assert_eq!(rec.models.len(), 1);
    assert!((rec.models[0].diameter_m - 0.15).abs() < 1e-12);
    assert_eq!(rec.ground_truth.as_ref().unwrap().len(), 2);
    let d = rec.depth_frame(3).unwrap();
    assert!((d.depth_m[0] - 0.503).abs() < 1e-6);
    let mut b = EventBuffer::new();
    let mut r = rec.events().unwrap();
    r.read_all(&mut b).unwrap();
    assert_eq!(b.cd, cd);
    assert_eq!(b.triggers, tr);
    assert!(
        rec.depth_frame(2)
            .unwrap_err()
            .to_string()
            .contains("000002.png")
    );
}

fn expect_error(corrupt: impl FnOnce(&Path), file: &str, words: &str) {
    let tmp = tempfile::tempdir().unwrap();
    write_sample(tmp.path());
    corrupt(tmp.path());
    let err = Recording::open(tmp.path()).unwrap_err().to_string();
    assert!(err.contains(file), "error `{err}` should name `{file}`");
    assert!(err.contains(words), "error `{err}` should say `{words}`");
}

#[test]
fn missing_files_are_named() {
    expect_error(
        |d| std::fs::remove_file(d.join("camera.json")).unwrap(),
        "camera.json",
        "missing",
    );
    expect_error(
        |d| std::fs::remove_file(d.join("events.raw")).unwrap(),
        "events.raw",
        "No such file",
    );
    expect_error(
        |d| std::fs::remove_file(d.join("models/can.obj")).unwrap(),
        "can.obj",
        "missing",
    );
    expect_error(
        |d| std::fs::remove_dir_all(d.join("depth")).unwrap(),
        "depth",
        "missing",
    );
}

#[test]
fn wrong_image_size_is_named() {
    expect_error(
        |d| {
            drivers::recording::write_depth_png(
                &d.join("depth/000001.png"),
                31,
                24,
                &vec![1; 31 * 24],
            )
            .unwrap()
        },
        "000001.png",
        "31x24",
    );
    expect_error(
        |d| std::fs::write(d.join("depth/000002.png"), b"not a png").unwrap(),
        "000002.png",
        "PNG",
    );
    expect_error(
        |d| std::fs::write(d.join("depth/notes.txt"), b"hi").unwrap(),
        "notes.txt",
        "unexpected file",
    );
}

#[test]
fn timestamps_going_back_and_unknown_objects_are_named() {
    let gt = |body: &str| format!("{}\n{body}", drivers::recording::GROUND_TRUTH_HEADER);
    expect_error(
        |d| {
            std::fs::write(
                d.join("groundtruth.csv"),
                gt("100,can,0,0,1,0,0,0,1\n50,can,0,0,1,0,0,0,1\n"),
            )
            .unwrap()
        },
        "groundtruth.csv",
        "goes back",
    );
    expect_error(
        |d| std::fs::write(d.join("groundtruth.csv"), gt("100,drill,0,0,1,0,0,0,1\n")).unwrap(),
        "groundtruth.csv",
        "`drill` is not in",
    );
}

#[test]
fn inconsistent_geometry_and_bad_json_are_named() {
    expect_error(
        |d| {
            let mut r = rig();
            r.event_camera.width = 1280;
            std::fs::write(d.join("camera.json"), serde_json::to_string(&r).unwrap()).unwrap();
        },
        "events.raw",
        "differs from camera.json",
    );
    expect_error(
        |d| std::fs::write(d.join("meta.json"), "{").unwrap(),
        "meta.json",
        "invalid",
    );
    // A misspelt key is not the default in disguise.
    expect_error(
        |d| {
            let mut rig = serde_json::to_value(rig()).unwrap();
            let scale = rig
                .as_object_mut()
                .unwrap()
                .remove("depth_scale_m")
                .unwrap();
            rig["depth_scale"] = scale;
            std::fs::write(d.join("camera.json"), rig.to_string()).unwrap();
        },
        "camera.json",
        "depth_scale",
    );
    // A schedule no timeline can follow.
    for (key, value, words) in [
        ("ticks_per_depth", "0", "ticks_per_depth is 0"),
        ("tick_rate_hz", "-120", "tick_rate_hz -120"),
        ("channel", "99", "channel 99"),
        ("wide_width_us", "50", "pulse widths"),
    ] {
        expect_error(
            |d| {
                let path = d.join("meta.json");
                let mut meta: serde_json::Value =
                    serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
                meta["trigger"][key] = serde_json::from_str(value).unwrap();
                std::fs::write(&path, meta.to_string()).unwrap();
            },
            "meta.json",
            words,
        );
    }
    expect_error(
        |d| {
            let mut r = rig();
            r.t_event_depth[0][0] = 2.0;
            std::fs::write(d.join("camera.json"), serde_json::to_string(&r).unwrap()).unwrap();
        },
        "camera.json",
        "orthonormal",
    );
}

/// A damaged copy of `bytes`: some bytes replaced, then cut short or not.
fn damage(bytes: &[u8], edits: &[(usize, u8)], keep: Option<usize>) -> Vec<u8> {
    let mut out = bytes.to_vec();
    for &(at, b) in edits {
        if !out.is_empty() {
            let i = at % out.len();
            out[i] = b;
        }
    }
    if let Some(k) = keep {
        out.truncate(k % (bytes.len() + 1));
    }
    out
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]

    /// A recording with one of its JSON files, its ground truth or a depth image damaged opens or is refused
    /// with an error naming a file of the recording, and never panics; a damaged depth image that opens is
    /// refused by name when its frame is read.
    #[test]
    fn damaged_files_are_refused_by_name(
        file in 0usize..5,
        edits in proptest::collection::vec((proptest::prelude::any::<usize>(), proptest::prelude::any::<u8>()), 0..6),
        keep in proptest::option::of(proptest::prelude::any::<usize>()),
    ) {
        let tmp = tempfile::tempdir().unwrap();
        write_sample(tmp.path());
        let name = ["camera.json", "meta.json", "models/models_info.json", "groundtruth.csv", "depth/000001.png"][file];
        let path = tmp.path().join(name);
        let bytes = std::fs::read(&path).unwrap();
        std::fs::write(&path, damage(&bytes, &edits, keep)).unwrap();
        let dir = tmp.path().display().to_string();
        match Recording::open(tmp.path()) {
            Err(e) => {
                // A damaged file may make another one the first to be refused (a renamed model's mesh, ground
                // truth naming an object models_info.json no longer lists), but some file of it is named.
                let message = e.to_string();
                let named = ["camera.json", "meta.json", "models/", "groundtruth.csv", "depth/", "events.raw"]
                    .iter()
                    .any(|f| message.contains(&format!("{dir}/{f}")));
                proptest::prop_assert!(named, "{}", message);
            }
            Ok(rec) => {
                for n in rec.depth_frames.clone() {
                    if let Err(e) = rec.depth_frame(n) {
                        let message = e.to_string();
                        proptest::prop_assert!(message.contains(&format!("{n:06}.png")), "{}", message);
                    }
                }
            }
        }
    }
}

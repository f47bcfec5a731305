//! The commands refuse input that would lose data or mislead before doing any work: an output that overwrites an
//! input, the same object or method twice, first poses that do not cover the objects, ground truth that covers
//! none of the ticks. Each case names what is wrong, exits non-zero and never panics.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod cli;

use cli::{eventtrack6d, fails_with};
use drivers::event::CdEvent;
use drivers::recording::{
    CameraIntrinsics, CameraRig, ModelInfo, PoseSample, RecordingMeta, RecordingWriter,
    TriggerSchedule,
};
use drivers::timeline::{TimelineConfig, ideal_edges};
use std::path::Path;

/// A 0.1 s recording (12 ticks, 3 depth frames) of a small tetrahedron `can` whose ground truth lies at `gt_us`.
fn recording(dir: &Path, gt_us: &[i64]) {
    let cam = |w: u32, h: u32| CameraIntrinsics {
        width: w,
        height: h,
        fx: 100.0,
        fy: 100.0,
        cx: f64::from(w) / 2.0,
        cy: f64::from(h) / 2.0,
        distortion: vec![],
    };
    let rig = CameraRig {
        event_camera: cam(64, 48),
        depth_camera: cam(32, 24),
        t_event_depth: [
            [1.0, 0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
            [0.0, 0.0, 0.0, 1.0],
        ],
        depth_scale_m: 0.001,
    };
    let mut w = RecordingWriter::create(dir, rig, "cli test").unwrap();
    let edges = ideal_edges(&TimelineConfig::default(), 1_000, 12);
    let cd: Vec<CdEvent> = (0..200)
        .map(|i| CdEvent {
            t_us: 1_000 + i * 500,
            x: (i % 64) as u16,
            y: (i % 48) as u16,
            polarity: i % 2 == 0,
        })
        .collect();
    w.write_events(&cd, &edges).unwrap();
    for n in 0..3 {
        w.write_depth_mm(n, &vec![500; 32 * 24]).unwrap();
    }
    std::fs::write(
        w.models_dir().join("can.obj"),
        "v 0 0 0\nv 0.05 0 0\nv 0 0.05 0\nv 0 0 0.05\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n",
    )
    .unwrap();
    let model = ModelInfo {
        name: "can".into(),
        diameter_m: 0.0707,
        min_m: [0.0, 0.0, 0.0],
        size_m: [0.05, 0.05, 0.05],
        symmetries_discrete: vec![],
        symmetries_continuous: vec![],
    };
    let meta = RecordingMeta {
        generator: "cli test".into(),
        trigger: TriggerSchedule::default(),
        parameters: Default::default(),
    };
    let gt: Vec<PoseSample> = gt_us
        .iter()
        .map(|&t| PoseSample {
            t_us: t,
            object: "can".into(),
            translation: [0.0, 0.0, 0.5],
            rotation_xyzw: [0.0, 0.0, 0.0, 1.0],
        })
        .collect();
    w.finish(&meta, &[model], Some(&gt)).unwrap();
}

const HEADER: &str = "t_us,object,x,y,z,qx,qy,qz,qw,quality,state\n";

#[test]
fn outputs_never_overwrite_inputs_or_each_other() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let rec = d.join("rec");
    recording(&rec, &[0, 200_000]);
    let rec_s = rec.to_str().unwrap();
    let events = rec.join("events.raw");
    let before = std::fs::read(&events).unwrap();
    // convert onto its own input, directly or through a link: refused, the input untouched.
    fails_with(
        &[
            "convert",
            events.to_str().unwrap(),
            events.to_str().unwrap(),
        ],
        "would overwrite the input",
    );
    let link = d.join("link.raw");
    std::os::unix::fs::symlink(&events, &link).unwrap();
    fails_with(
        &["convert", events.to_str().unwrap(), link.to_str().unwrap()],
        "would overwrite the input",
    );
    assert_eq!(std::fs::read(&events).unwrap(), before);
    // CSV text into a `.raw` name, or --to against the extension.
    let out_raw = d.join("out.raw");
    fails_with(
        &[
            "convert",
            events.to_str().unwrap(),
            out_raw.to_str().unwrap(),
            "--to",
            "csv",
        ],
        "would write text into a `.raw` file",
    );
    let out_csv = d.join("out.csv");
    fails_with(
        &[
            "convert",
            events.to_str().unwrap(),
            out_csv.to_str().unwrap(),
            "--to",
            "evt2",
        ],
        "contradicts the extension",
    );
    // track: the poses onto the ground truth, or the trace onto the poses.
    let gt = rec.join("groundtruth.csv");
    fails_with(
        &["track", rec_s, "--out", gt.to_str().unwrap()],
        "would overwrite the recording's ground truth",
    );
    let poses = d.join("poses.csv");
    fails_with(
        &[
            "track",
            rec_s,
            "--out",
            poses.to_str().unwrap(),
            "--fallback-trace",
            poses.to_str().unwrap(),
        ],
        "--out and --fallback-trace name the same file",
    );
    let nowhere = d.join("no/such/folder/poses.csv");
    fails_with(
        &["track", rec_s, "--out", nowhere.to_str().unwrap()],
        "does not exist",
    );
    // eval: the JSON onto the predictions.
    let pred = d.join("pred.csv");
    std::fs::write(
        &pred,
        format!("{HEADER}1000,can,0,0,0.5,0,0,0,1,1,tracking\n"),
    )
    .unwrap();
    fails_with(
        &[
            "eval",
            "--pred",
            pred.to_str().unwrap(),
            "--gt",
            rec_s,
            "--json",
            pred.to_str().unwrap(),
        ],
        "--json",
    );
    fails_with(
        &[
            "eval",
            "--pred",
            pred.to_str().unwrap(),
            "--gt",
            rec_s,
            "--json",
            pred.to_str().unwrap(),
        ],
        "would overwrite the --pred it reads",
    );
    // Nor onto a model of the recording.
    let info = rec.join("models").join("models_info.json");
    fails_with(
        &[
            "eval",
            "--pred",
            pred.to_str().unwrap(),
            "--gt",
            rec_s,
            "--json",
            info.to_str().unwrap(),
        ],
        "would overwrite the recording's models",
    );
    assert!(std::fs::read_to_string(&pred).unwrap().starts_with(HEADER));
}

#[test]
fn a_failed_conversion_leaves_no_partial_output_and_touches_nothing_it_did_not_write() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // An input refused before anything is written: an existing file at the output stays as it was.
    let bad = d.join("bad.raw");
    std::fs::write(&bad, "not a raw file\n").unwrap();
    let keep = d.join("keep.csv");
    std::fs::write(&keep, "precious\n").unwrap();
    fails_with(
        &["convert", bad.to_str().unwrap(), keep.to_str().unwrap()],
        "bad.raw",
    );
    assert_eq!(std::fs::read_to_string(&keep).unwrap(), "precious\n");
    // An input that fails half-way: the partial output is removed.
    let csv = d.join("events.csv");
    let mut text = String::from("t_us,x,y,p\n");
    for i in 0..50_000 {
        text.push_str(&format!("{},{},{},1\n", i * 10, i % 640, i % 480));
    }
    text.push_str("oops,1,1,1\n");
    std::fs::write(&csv, text).unwrap();
    let out = d.join("out.raw");
    fails_with(
        &["convert", csv.to_str().unwrap(), out.to_str().unwrap()],
        "oops",
    );
    assert!(!out.exists(), "the partial output was left behind");
}

#[test]
fn first_poses_and_objects_must_cover_what_is_tracked() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let rec = d.join("rec");
    recording(&rec, &[0, 200_000]);
    let rec_s = rec.to_str().unwrap();
    let out = d.join("poses.csv");
    let out = out.to_str().unwrap();
    fails_with(
        &["track", rec_s, "--out", out, "--objects", "can,can"],
        "--objects: `can` is given twice",
    );
    let first = d.join("first.csv");
    std::fs::write(&first, HEADER).unwrap();
    let first_s = first.to_str().unwrap();
    fails_with(
        &["track", rec_s, "--out", out, "--first-poses", first_s],
        "holds no poses",
    );
    std::fs::write(
        &first,
        format!("{HEADER}1000,cup,0,0,0.5,0,0,0,1,1,tracking\n"),
    )
    .unwrap();
    fails_with(
        &[
            "track",
            rec_s,
            "--out",
            out,
            "--first-poses",
            first_s,
            "--objects",
            "can",
        ],
        "no first pose for `can` (objects there: cup)",
    );
    std::fs::write(
        &first,
        format!("{HEADER}99000000,can,0,0,0.5,0,0,0,1,1,tracking\n"),
    )
    .unwrap();
    fails_with(
        &["track", rec_s, "--out", out, "--first-poses", first_s],
        "comes after the recording's last tick",
    );
    fails_with(
        &["track", rec_s, "--out", out, "--init-noise", "5,1e9"],
        "centimetres `1e9` is over 100",
    );
    fails_with(
        &["track", rec_s, "--out", out, "--seed", "3"],
        "--init-noise",
    );
    fails_with(
        &["track", rec_s, "--out", out, "--overlay-every", "3"],
        "--overlay",
    );
    assert!(!Path::new(out).exists(), "nothing was tracked");
}

#[test]
fn ground_truth_must_cover_the_ticks_it_scores() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let pred = d.join("pred.csv");
    std::fs::write(
        &pred,
        format!("{HEADER}1000,can,0,0,0.5,0,0,0,1,1,tracking\n"),
    )
    .unwrap();
    let pred = pred.to_str().unwrap();
    // Ground truth 10 s after the recording's 12 ticks: nothing to score, said so.
    let far = d.join("far");
    recording(&far, &[10_000_000, 10_100_000]);
    fails_with(
        &["eval", "--pred", pred, "--gt", far.to_str().unwrap()],
        "covers none of the recording's 12 ticks",
    );
    // Ground truth over the first ticks only: scored there, and the count is warned about.
    let part = d.join("part");
    recording(&part, &[0, 30_000]);
    let out = eventtrack6d(&["eval", "--pred", pred, "--gt", part.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("`can` scored at 4 of 12 ticks"), "{stderr}");
    // A quality outside [0, 1] or an unknown state is a bad row.
    let bad = d.join("bad.csv");
    std::fs::write(
        &bad,
        format!("{HEADER}1000,can,0,0,0.5,0,0,0,1,1.5,tracking\n"),
    )
    .unwrap();
    fails_with(
        &[
            "eval",
            "--pred",
            bad.to_str().unwrap(),
            "--gt",
            part.to_str().unwrap(),
        ],
        "quality `1.5` is not in [0, 1]",
    );
}

#[test]
fn demo_parameters_are_checked_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cache = d.join("cache");
    let cache_s = cache.to_str().unwrap();
    for (name, text, needle) in [
        ("unknown.toml", "no_such_key = 1\n", "no_such_key"),
        ("negative.toml", "inner_step_px = -1.0\n", "inner_step_px"),
    ] {
        let params = d.join(name);
        std::fs::write(&params, text).unwrap();
        let params_s = params.to_str().unwrap();
        let args = [
            "demo",
            "--params",
            params_s,
            "--cache-dir",
            cache_s,
            "--no-zenoh",
        ];
        fails_with(&args, &format!("{params_s}: invalid tracker parameters"));
        fails_with(&args, needle);
        assert!(!cache.exists(), "{name}: the demo generated a sequence");
    }
}

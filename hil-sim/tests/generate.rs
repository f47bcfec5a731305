//! Recordings from the generator: deterministic, consistent with the trigger schedule and the ESIM model,
//! and readable by the project's decoder and an independent EVT3 reader.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use drivers::event::EventBuffer;
use drivers::recording::Recording;
use drivers::timeline::ideal_edges;
use hil_sim::esim::{EsimConfig, EventSimulator};
use hil_sim::generate::{Companion, GenerateConfig, ObjectSource, generate, sensor_log_at};
use hil_sim::motion::{MotionProfile, SpeedLevel};
use hil_sim::objects::ObjectKind;
use std::path::Path;

fn config(seconds: f64) -> GenerateConfig {
    let mut c = GenerateConfig::new(
        ObjectSource::Library(ObjectKind::Mug),
        MotionProfile::Translation,
        SpeedLevel::Moderate,
        seconds,
        5,
    );
    c.esim = EsimConfig {
        refractory_us: 0.0,
        noise_rate_hz: 0.0,
        ..EsimConfig::default()
    };
    c
}

fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.push((
                    p.strip_prefix(dir).unwrap().display().to_string(),
                    std::fs::read(&p).unwrap(),
                ));
            }
        }
    }
    out.sort();
    out
}

#[test]
fn same_seed_gives_byte_identical_recordings_and_triggers_follow_the_schedule() {
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let cfg = config(0.1);
    generate(&cfg, a.path(), |_| {}).unwrap();
    generate(&cfg, b.path(), |_| {}).unwrap();
    let (fa, fb) = (files(a.path()), files(b.path()));
    assert!(
        fa.len() >= 8,
        "{:?}",
        fa.iter().map(|f| &f.0).collect::<Vec<_>>()
    );
    assert_eq!(fa.len(), fb.len());
    for ((na, da), (nb, db)) in fa.iter().zip(&fb) {
        assert_eq!(na, nb);
        assert!(da == db, "{na} differs between two runs with the same seed");
    }
    let mut other = cfg.clone();
    other.seed = 6;
    let c = tempfile::tempdir().unwrap();
    generate(&other, c.path(), |_| {}).unwrap();
    assert_ne!(
        std::fs::read(a.path().join("events.raw")).unwrap(),
        std::fs::read(c.path().join("events.raw")).unwrap()
    );

    let rec = Recording::open(a.path()).unwrap();
    let mut events = EventBuffer::new();
    let mut reader = rec.events().unwrap();
    reader.read_all(&mut events).unwrap();
    assert_eq!(reader.anomalies().total(), 0);
    assert!(events.cd.len() > 10_000, "{} events", events.cd.len());
    let tl = rec.meta.trigger.timeline_config();
    let expected: Vec<_> = ideal_edges(&tl, 500, 20)
        .into_iter()
        .filter(|e| e.t_us < 100_000)
        .collect();
    assert_eq!(
        events.triggers, expected,
        "trigger edges exactly where the schedule puts them"
    );
    // Depth exposures at pulses 0, 4, 8: frames 0, 1, 2.
    assert_eq!(rec.depth_frames, vec![0, 1, 2]);
    assert!(rec.ground_truth.as_ref().unwrap().len() >= 100);
}

#[test]
fn a_write_error_on_the_sensor_thread_stops_generation_and_names_the_file() {
    // The sensor half (events, depth files) runs on its own thread behind the renderer: its failure must reach
    // the caller, and rendering must stop rather than wait for a sensor that is gone.
    let dir = tempfile::tempdir().unwrap();
    let blocked = dir.path().join("depth").join("000001.png");
    std::fs::create_dir_all(&blocked).unwrap();
    let mut last_progress = 0.0;
    let err = generate(&config(0.5), dir.path(), |t| last_progress = t)
        .expect_err("the second depth frame cannot be written");
    let message = err.to_string();
    assert!(message.contains("000001.png"), "{message}");
    // The second frame is exposed at 33 ms; the renderer runs at most a few steps ahead of the failure.
    assert!(
        last_progress < 0.1,
        "rendering went on to {last_progress} s"
    );
}

#[test]
fn event_polarities_integrate_to_the_change_in_log_intensity() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = config(0.1);
    generate(&cfg, dir.path(), |_| {}).unwrap();
    let rec = Recording::open(dir.path()).unwrap();
    let mut events = EventBuffer::new();
    rec.events().unwrap().read_all(&mut events).unwrap();
    // From the start (where every pixel's reference equals its log intensity) to a tick (the generator
    // renders exactly at ticks): the reference stays within one threshold of the log intensity, so the
    // integrated events are within one threshold of the change.
    let (t1, t2) = (0i64, 500 + (5.0 * 1e6_f64 / 120.0).round() as i64);
    let l1 = sensor_log_at(&cfg, t1 as f64 * 1e-6).unwrap();
    let l2 = sensor_log_at(&cfg, t2 as f64 * 1e-6).unwrap();
    let (w, h) = (1280usize, 720usize);
    let thresholds = EventSimulator::new(w as u32, h as u32, cfg.esim, cfg.seed, &vec![0.0; w * h]);
    let mut sum = vec![0.0f64; w * h];
    // A crossing within the microsecond after t2 is stamped t2 like one exactly at t2: both are counted; the
    // tolerance below allows for those rare boundary events.
    for e in events.cd.iter().filter(|e| e.t_us >= t1 && e.t_us <= t2) {
        let (cp, cn) = thresholds.thresholds(u32::from(e.x), u32::from(e.y));
        sum[usize::from(e.y) * w + usize::from(e.x)] += if e.polarity {
            f64::from(cp)
        } else {
            -f64::from(cn)
        };
    }
    let (mut checked, mut within_one, mut within_two) = (0u64, 0u64, 0u64);
    for i in (0..w * h).step_by(7) {
        let dl = f64::from(l2[i] - l1[i]);
        if dl.abs() < 0.05 && sum[i] == 0.0 {
            continue;
        }
        let (cp, cn) = thresholds.thresholds((i % w) as u32, (i / w) as u32);
        let c = f64::from(cp.max(cn));
        checked += 1;
        within_one += u64::from((sum[i] - dl).abs() <= c);
        within_two += u64::from((sum[i] - dl).abs() <= 2.0 * c);
    }
    assert!(checked > 500, "only {checked} changing pixels sampled");
    let one = within_one as f64 / checked as f64;
    assert!(
        one > 0.999,
        "{one:.4} of {checked} pixels within one threshold"
    );
    assert_eq!(within_two, checked, "every pixel within two thresholds");
}

/// Reads the events with an independent EVT3 reader (the `evlib` Python package, installed by `.ci/setup`):
/// same count, same ON count, same coordinate and time sums.
#[test]
fn independent_evt3_reader_counts_the_same_events() {
    let dir = tempfile::tempdir().unwrap();
    let mut cfg = config(0.05);
    cfg.esim.noise_rate_hz = 0.5;
    generate(&cfg, dir.path(), |_| {}).unwrap();
    let raw = dir.path().join("events.raw");
    let mut events = EventBuffer::new();
    Recording::open(dir.path())
        .unwrap()
        .events()
        .unwrap()
        .read_all(&mut events)
        .unwrap();
    let script = "import sys, evlib, polars as pl\n\
        df = evlib.load_events(sys.argv[1]).collect()\n\
        t = df['t'].cast(pl.Int64)\n\
        print(df.height, int((df['polarity'] == 1).sum()), int(df['x'].cast(pl.Int64).sum()), \
        int(df['y'].cast(pl.Int64).sum()), int(t.sum()))\n";
    let out = std::process::Command::new("python3")
        .arg("-c")
        .arg(script)
        .arg(&raw)
        .output();
    let out = match out {
        Ok(o) if o.status.success() => o,
        Ok(o) => panic!(
            "the independent reader failed (install it with `bash .ci/setup`, i.e. `pip install evlib`): {}",
            String::from_utf8_lossy(&o.stderr)
        ),
        Err(e) => panic!("python3 is needed for the independent EVT3 reader: {e}"),
    };
    let text = String::from_utf8_lossy(&out.stdout);
    // The figures are the last line (a library may print notices before them).
    let last = text.lines().last().unwrap_or_default();
    let v: Vec<i64> = last
        .split_whitespace()
        .map(|v| {
            v.parse::<i64>()
                .unwrap_or_else(|_| panic!("unexpected reader output: {text}"))
        })
        .collect();
    let ours = [
        events.cd.len() as i64,
        events.cd.iter().filter(|e| e.polarity).count() as i64,
        events.cd.iter().map(|e| i64::from(e.x)).sum(),
        events.cd.iter().map(|e| i64::from(e.y)).sum(),
        events.cd.iter().map(|e| e.t_us).sum(),
    ];
    assert_eq!(
        v, ours,
        "[count, ON count, sum x, sum y, sum t] from evlib vs ours"
    );
}

#[test]
fn a_user_obj_with_material_and_texture_is_copied_into_the_recording() {
    let src = tempfile::tempdir().unwrap();
    let files =
        hil_sim::objects::write_object(&hil_sim::objects::generate(ObjectKind::Can, 3), src.path())
            .unwrap();
    // A user's file name with characters that are not file-name safe for the object name.
    let user = src.path().join("my can.obj");
    std::fs::rename(&files.obj, &user).unwrap();
    let out = tempfile::tempdir().unwrap();
    let mut cfg = config(0.02);
    cfg.object = ObjectSource::File(user);
    generate(&cfg, out.path(), |_| {}).unwrap();
    let rec = Recording::open(out.path()).unwrap();
    assert_eq!(rec.models.len(), 1);
    assert_eq!(rec.models[0].name, "my_can");
    assert!(
        rec.models[0].symmetries_continuous.is_empty(),
        "nothing is assumed about a user mesh"
    );
    for f in ["my_can.obj", "can.mtl", "can.png"] {
        assert!(out.path().join("models").join(f).is_file(), "{f} copied");
    }
    let loaded = scene::mesh::load_obj(&rec.mesh_path("my_can"), &Default::default()).unwrap();
    assert!((loaded.mesh.diameter() - rec.models[0].diameter_m).abs() < 1e-9);
}

/// Pixels of depth frame 0 nearer than `metres` (and measured).
fn depth_pixels_nearer_than(dir: &Path, metres: f32) -> usize {
    let rec = Recording::open(dir).unwrap();
    let frame = rec.depth_frame(0).unwrap();
    frame
        .depth_m
        .iter()
        .filter(|&&z| z > 0.0 && z < metres)
        .count()
}

#[test]
fn a_companion_object_is_rendered_and_in_the_ground_truth() {
    let mut cfg = config(0.05);
    cfg.companions.push(Companion {
        object: ObjectSource::Library(ObjectKind::Can),
        motion: MotionProfile::HandSwitch,
        speed: SpeedLevel::Moderate,
        offset_m: Companion::default_offset(1),
    });
    let out = tempfile::tempdir().unwrap();
    generate(&cfg, out.path(), |_| {}).unwrap();
    let rec = Recording::open(out.path()).unwrap();
    let names: Vec<&str> = rec.models.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["can", "mug"]);
    assert!(out.path().join("models/can.obj").is_file());
    // Both objects at every ground-truth time, the can on its own trajectory 15 cm nearer the camera.
    let gt = rec.ground_truth.as_deref().unwrap();
    let (cans, mugs): (Vec<_>, Vec<_>) = gt.iter().partition(|s| s.object == "can");
    assert_eq!(cans.len(), mugs.len());
    assert!(cans.len() >= 50, "{} rows", cans.len());
    for (c, m) in cans.iter().zip(&mugs) {
        assert_eq!(c.t_us, m.t_us);
        assert!(
            (c.translation[2] - (m.translation[2] - 0.15)).abs() < 0.1,
            "{c:?} {m:?}"
        );
    }
    assert_eq!(rec.meta.parameters["companions"][0]["object"], "can");
    // The depth camera sees the can in front of everything the single-object scene has.
    let near = depth_pixels_nearer_than(out.path(), 0.54);
    let alone = tempfile::tempdir().unwrap();
    cfg.companions.clear();
    generate(&cfg, alone.path(), |_| {}).unwrap();
    let near_alone = depth_pixels_nearer_than(alone.path(), 0.54);
    assert!(
        near > 1000 && near_alone < near / 10,
        "pixels nearer than 0.54 m: {near} with the can, {near_alone} without"
    );
    assert!(
        Recording::open(alone.path())
            .unwrap()
            .meta
            .parameters
            .get("companions")
            .is_none(),
        "a single-object recording's metadata carries no companions"
    );
}

#[test]
fn objects_of_one_recording_need_distinct_names_and_sensible_offsets() {
    let out = tempfile::tempdir().unwrap();
    let mut cfg = config(0.02);
    cfg.companions.push(Companion {
        object: ObjectSource::Library(ObjectKind::Mug),
        motion: MotionProfile::Shake,
        speed: SpeedLevel::Slow,
        offset_m: [0.1, 0.0, 0.0],
    });
    let e = generate(&cfg, out.path(), |_| {}).unwrap_err().to_string();
    assert!(e.contains("two objects named `mug`"), "{e}");
    cfg.companions[0].object = ObjectSource::Library(ObjectKind::Can);
    cfg.companions[0].offset_m = [0.0, 0.0, -0.5];
    let e = generate(&cfg, out.path(), |_| {}).unwrap_err().to_string();
    assert!(
        e.contains("companion 1 offset") && e.contains("0.25 m"),
        "{e}"
    );
    cfg.companions[0].offset_m = [f64::NAN, 0.0, 0.0];
    assert!(generate(&cfg, out.path(), |_| {}).is_err());
}

//! End to end: a short simulated recording, the benchmark's methods run over it with only the first pose given,
//! and the evaluation moving the right way as the oracle's noise grows.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use drivers::recording::Recording;
use eval::bench::{
    MethodResults, SuiteSequence, expand_seeds, method_from_spec, method_from_spec_with,
    open_sequence, run_sequence,
};
use eval::quality_report::method_quality_report;
use eval::report::{results_json, results_markdown};
use eval::{AucLimit, evaluate_object};
use eventtrack6d_tests::shipped_params::ticks_only;
use hil_sim::generate::{Companion, GenerateConfig, ObjectSource, generate};
use hil_sim::motion::{MotionProfile, SpeedLevel};
use hil_sim::objects::ObjectKind;
use tracker::recording::{PoseTrack, format_pose_csv, parse_pose_csv, recording_ticks};

fn run(spec: &str, seq: &SuiteSequence) -> MethodResults {
    let (rec, ticks) = open_sequence(seq).unwrap();
    let mut m = method_from_spec(spec).unwrap();
    MethodResults {
        name: spec.into(),
        sequences: run_sequence(m.as_mut(), seq, &rec, &ticks).unwrap(),
        parameters: m.parameters(),
    }
}

#[test]
fn bench_methods_on_a_short_recording() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = GenerateConfig::new(
        ObjectSource::Library(ObjectKind::Can),
        MotionProfile::Shake,
        SpeedLevel::Moderate,
        0.2,
        3,
    );
    generate(&cfg, dir.path(), |_| {}).unwrap();
    let seq = SuiteSequence {
        name: "can-shake-moderate".into(),
        dir: dir.path().to_path_buf(),
        motion: "shake".into(),
        speed: "moderate".into(),
    };

    // Exact ground truth: full marks at 120 Hz and 30 Hz, with the measured depth frames in VSD.
    let exact = run("gt-noise:0:0", &seq);
    let s = exact.sequences[0].scores.summary(false, AucLimit::Diameter);
    assert!(s.frames >= 20, "{s:?}");
    assert_eq!((s.add_s, s.add, s.ar), (100.0, 100.0, 100.0));
    let s30 = exact.sequences[0].scores.summary(true, AucLimit::Diameter);
    assert!(s30.frames >= 5 && s30.frames < s.frames);
    assert_eq!(s30.ar, 100.0);

    // Noise grows -> every score falls; the static pose is far worse than small noise on a shaking object.
    let small = run("gt-noise:2:1", &seq).mean(false, AucLimit::Diameter);
    let large_run = run("gt-noise:15:6", &seq);
    let large = large_run.mean(false, AucLimit::Diameter);
    let stat = run("static", &seq);
    let st = stat.mean(false, AucLimit::Diameter);
    assert!(
        small.add > large.add && small.add_s > large.add_s && small.ar > large.ar,
        "{small:?} {large:?}"
    );
    assert!(small.ar > st.ar && small.add > st.add, "{small:?} {st:?}");
    // ADD-S never below ADD for the same poses.
    assert!(small.add_s >= small.add && large.add_s >= large.add);

    // Report shapes.
    let doc = results_json("test", &[stat.clone(), exact.clone()], AucLimit::Diameter);
    let m = &doc["methods"]["gt-noise:0:0"];
    assert_eq!(m["mean"]["ar"].as_f64(), Some(100.0));
    assert!(m["mean_30hz"]["add_s"].is_number() && m["update_hz"].is_number());
    assert!(m["parameters"].is_null(), "{}", m["parameters"]);
    let sq = &m["sequences"]["can-shake-moderate"];
    assert_eq!(sq["object"], "can");
    assert_eq!(sq["motion"], "shake");
    assert_eq!(sq["speed"], "moderate");
    // The quality section: exact poses never fail; every scored tick lands in a band; a constant quality
    // correlates with nothing.
    let q = &m["quality"];
    assert_eq!(
        (q["sequences"].as_u64(), q["failed"].as_u64()),
        (Some(1), Some(0))
    );
    assert!(q["spearman"].is_null(), "{q}");
    let banded: u64 = q["bands"]
        .as_array()
        .unwrap()
        .iter()
        .map(|b| b["ticks"].as_u64().unwrap())
        .sum();
    assert_eq!(banded, s.frames as u64);
    // 15 mm per axis on a can (diameter about 12 cm) is off by more than a tenth of the diameter on most ticks:
    // failed, and the oracle never says `lost`.
    let noisy = method_quality_report(&large_run);
    assert_eq!(
        (
            noisy.failed,
            noisy.failed_with_lost,
            noisy.lost_without_failure
        ),
        (1, 0, 0)
    );
    // ... and is named as a failure the state kept quiet about.
    assert_eq!(noisy.silent_failures, ["can-shake-moderate"]);
    assert!(noisy.false_alarms.is_empty());
    // Its ticks off the object are counted, and none of them was announced.
    assert!(noisy.off_ticks > 0, "{noisy:?}");
    assert_eq!((noisy.lost_ticks, noisy.off_ticks_lost), (0, 0));
    let md = results_markdown("test", &[stat, exact.clone()], AucLimit::Metres);
    assert!(
        md.contains("| can |") && md.contains("| **MEAN** |") && md.contains("update rate (Hz)")
    );
    assert!(
        md.contains("## Quality and `lost` against the error"),
        "{md}"
    );
    // Exact poses: nothing to name under the quality table.
    assert!(
        md.contains("- gt-noise:0:0: failed without `lost`: none; `lost` without failure: none."),
        "{md}"
    );

    // Seeds of one first-pose error form a group: different first poses, one row of spread in the report.
    let seeded: Vec<MethodResults> = expand_seeds(&["depth30@4:3".to_string()], 2)
        .iter()
        .map(|spec| {
            let mut r = run(spec, &seq);
            r.name = method_from_spec(spec).unwrap().name().to_string();
            r
        })
        .collect();
    assert_eq!(
        seeded.iter().map(|r| r.name.as_str()).collect::<Vec<_>>(),
        ["depth30@4,3", "depth30@4,3,s2"]
    );
    let first = |r: &MethodResults| r.sequences[0].records[0].pose;
    assert!(
        (first(&seeded[0]).translation.vector - first(&seeded[1]).translation.vector).norm() > 1e-3,
        "seeds 1 and 2 start from the same pose"
    );
    let all = [seeded.clone(), vec![exact.clone()]].concat();
    let doc = results_json("test", &all, AucLimit::Diameter);
    let spread = doc["seed_spread"].as_array().unwrap();
    assert_eq!(spread.len(), 1, "{spread:?}");
    assert_eq!(spread[0]["group"], "depth30@4,3");
    let runs = spread[0]["runs"].as_array().unwrap();
    assert_eq!(
        runs.iter()
            .map(|r| r["seed"].as_u64().unwrap())
            .collect::<Vec<_>>(),
        [1, 2]
    );
    for (r, m) in runs.iter().zip(&seeded) {
        let mean = m.mean(false, AucLimit::Diameter).add_s;
        assert!((r["add_s"].as_f64().unwrap() - mean).abs() < 1e-9);
    }
    let md = results_markdown("test", &all, AucLimit::Diameter);
    assert!(md.contains("## Spread over first-pose seeds"), "{md}");
    assert!(md.contains("| depth30@4,3 | 2 |"), "{md}");
    assert!(
        md.contains("- depth30@4,3: slow / moderate sequences with `lost`:"),
        "{md}"
    );
    // Without seed groups there is no such section.
    assert!(
        !results_markdown("test", std::slice::from_ref(&exact), AucLimit::Diameter)
            .contains("first-pose seeds")
    );

    // The pose CSV round trip scores the same as the in-memory poses.
    let rec = Recording::open(dir.path()).unwrap();
    let ticks = recording_ticks(&rec).unwrap();
    let gt = PoseTrack::from_samples(rec.ground_truth.as_deref().unwrap(), "can");
    let rows: Vec<_> = ticks
        .iter()
        .filter_map(|t| {
            gt.interpolated_at(t.t_us)
                .map(|pose| tracker::recording::PoseRecord {
                    t_us: t.t_us,
                    object: "can".into(),
                    pose,
                    quality: 1.0,
                    state: "tracking".into(),
                })
        })
        .collect();
    let parsed = parse_pose_csv(&format_pose_csv(&rows)).unwrap();
    let scores = evaluate_object(
        &rec,
        &ticks,
        "can",
        &PoseTrack::from_records(&parsed, "can"),
    )
    .unwrap();
    let s = scores.summary(false, AucLimit::Diameter);
    // (re-normalising the parsed quaternions leaves errors of ~1e-17 m: above the zero threshold only)
    assert!(s.add_s > 99.9 && s.add > 99.9 && s.ar > 99.9, "{s:?}");
}

#[test]
fn the_objects_of_a_recording_are_tracked_together() {
    let dir = tempfile::tempdir().unwrap();
    let mut cfg = GenerateConfig::new(
        ObjectSource::Library(ObjectKind::Mug),
        MotionProfile::Translation,
        SpeedLevel::Slow,
        0.3,
        4,
    );
    cfg.companions.push(Companion {
        object: ObjectSource::Library(ObjectKind::Can),
        motion: MotionProfile::HandSwitch,
        speed: SpeedLevel::Slow,
        offset_m: Companion::default_offset(1),
    });
    generate(&cfg, dir.path(), |_| {}).unwrap();
    let seq = SuiteSequence {
        name: "mug-can".into(),
        dir: dir.path().to_path_buf(),
        motion: "translation".into(),
        speed: "slow".into(),
    };
    let (rec, ticks) = open_sequence(&seq).unwrap();
    // One refinement per tick (`config/tracker/ticks-only.toml`): this 0.3 s scene is one of the flips between
    // kept and lost, and with the defaults the mug is lost from its first ticks (ADD-S 10.3 against 20.6 held
    // still); what is checked here is that the bench tracks and scores the objects together.
    let mut m = method_from_spec_with("eventtrack6d", &ticks_only()).unwrap();
    let results = run_sequence(m.as_mut(), &seq, &rec, &ticks).unwrap();
    let names: Vec<&str> = results.iter().map(|r| r.scores.object.as_str()).collect();
    assert_eq!(names, ["can", "mug"]);
    let held = run("static", &seq);
    for (r, h) in results.iter().zip(&held.sequences) {
        assert!(r.records.len() >= ticks.len() - 1, "{}", r.records.len());
        assert!(r.records.iter().all(|p| p.object == r.scores.object));
        // Each is followed: closer to the truth than its first pose held still, by ADD-S (the can's turn about its
        // axis shows in neither its depth nor its outline, so ADD does not say whether it was followed).
        let (s, h) = (
            r.scores.summary(false, AucLimit::Diameter),
            h.scores.summary(false, AucLimit::Diameter),
        );
        assert!(
            s.add_s > h.add_s + 10.0,
            "{}: {s:?} against {h:?}",
            r.scores.object
        );
    }
    // Tracked together: one tracker run, each object charged half of it.
    assert_eq!(results[0].seconds, results[1].seconds);
}

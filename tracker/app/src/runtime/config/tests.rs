use super::load::key_at;
use super::*;
use std::path::Path;

fn parse(text: &str) -> Result<Config, ConfigError> {
    from_toml(text, "test.toml")
}

#[test]
fn builtin_default_is_the_demo() {
    let c = builtin_default().unwrap();
    assert_eq!(c.source.kind, SourceKind::Demo);
    assert_eq!(c.source.pace, Pace::Realtime);
    assert!(c.sinks.zenoh && c.sinks.csv && c.can.enabled);
    assert!(c.can.candump_log.is_some() && c.can.interface.is_none());
    assert_eq!(c.tracker.method, "eventtrack6d");
}

#[test]
fn unknown_key_is_named() {
    let e = parse("[source]\nkind = \"demo\"\n\n[zenoh]\nmode = \"peer\"\nlisten_on = []\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("line 6"), "{e}");
    assert!(e.contains("`zenoh.listen_on`"), "{e}");
    assert!(e.contains("unknown field `listen_on`"), "{e}");
}

#[test]
fn wrong_type_is_named() {
    let e = parse("[source]\nkind = \"demo\"\n[queue]\nevent_batches = \"many\"\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("`queue.event_batches`"), "{e}");
    assert!(e.contains("invalid type"), "{e}");
    let e = parse("[source]\nkind = \"usb\"\n").unwrap_err().to_string();
    assert!(e.contains("`source.kind`") && e.contains("usb"), "{e}");
    let e = parse("[source]\nkind = \"demo\"\n[tracker]\nrenderer = \"tpu\"\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("`tracker.renderer`") && e.contains("tpu"), "{e}");
    let c = parse("[source]\nkind = \"demo\"\n[tracker]\nrenderer = \"gpu\"\n").unwrap();
    assert_eq!(c.tracker.renderer, scene::render::RendererKind::Gpu);
}

#[test]
fn tracker_parameters_are_read_and_checked() {
    let c = parse(
        "[source]\nkind = \"demo\"\n[tracker.parameters]\nobject_threads = 2\n\
         [tracker.parameters.redetect]\nplaces_per_tick = 3\n",
    )
    .unwrap();
    assert_eq!(c.tracker.parameters.execution.object_threads, 2);
    assert_eq!(c.tracker.parameters.redetect.places_per_tick, 3);
    // Keys not given keep their defaults.
    assert_eq!(
        c.tracker.parameters.roi.roi_size,
        tracker::track::TrackerConfig::default().roi.roi_size
    );
    let e = parse("[source]\nkind = \"demo\"\n[tracker.parameters]\nroi_sise = 128\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("roi_sise") && e.contains("line 4"), "{e}");
    let e = parse("[source]\nkind = \"demo\"\n[tracker.parameters]\nobject_threads = 300\n")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("`tracker.parameters.object_threads`") && e.contains("300"),
        "{e}"
    );
}

#[test]
fn out_of_range_values_are_named() {
    let e = parse("[source]\nkind = \"demo\"\n[status]\nperiod_ms = 0\n")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("`status.period_ms`") && e.contains("out of range"),
        "{e}"
    );
    let e = parse("[source]\nkind = \"demo\"\n[tracker]\nrealtime_priority = 120\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("`tracker.realtime_priority`"), "{e}");
    let e = parse("[source]\nkind = \"demo\"\n[queue]\nbatch_us = 5\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("`queue.batch_us`"), "{e}");
    let e = parse("[source]\nkind = \"demo\"\n[demo]\nseconds = 1000.0\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("`demo.seconds`"), "{e}");
    let e = parse("[source]\nkind = \"demo\"\n[demo]\nobject = \"teapot\"\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("`demo.object`") && e.contains("teapot"), "{e}");
    for bad in ["-5.0", "1500.0", "nan"] {
        let e = parse(&format!(
            "[source]\nkind = \"demo\"\ndepth_latency_ms = {bad}\n"
        ))
        .unwrap_err()
        .to_string();
        assert!(e.contains("`source.depth_latency_ms`"), "{bad}: {e}");
    }
    let ok = parse("[source]\nkind = \"demo\"\ndepth_latency_ms = 40.0\n").unwrap();
    assert_eq!(ok.source.depth_latency_ms, 40.0);
    for bad in ["-1.0", "1000.5", "nan"] {
        let e = parse(&format!(
            "[source]\nkind = \"demo\"\ndepth_latency_jitter_ms = {bad}\n"
        ))
        .unwrap_err()
        .to_string();
        assert!(e.contains("`source.depth_latency_jitter_ms`"), "{bad}: {e}");
    }
    let ok = parse("[source]\nkind = \"demo\"\ndepth_latency_jitter_ms = 20.0\n").unwrap();
    assert_eq!(ok.source.depth_latency_jitter_ms, 20.0);
}

#[test]
fn a_simulated_depth_latency_is_refused_for_a_live_source() {
    let e = parse(
        "[source]\nkind = \"live\"\ndepth_latency_ms = 30.0\n[live]\nevent_camera = \"evk4\"\ndepth_camera = \"d435i\"\n\
         depth_device = \"/dev/video2\"\ncalibration = \"camera.json\"\n",
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("`source.depth_latency_ms`") && e.contains("live source has its own"),
        "{e}"
    );
}

#[test]
fn missing_table_and_missing_key() {
    let e = parse("[source]\nkind = \"replay\"\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("`replay`") && e.contains("recording"), "{e}");
    let e = parse("[source]\npace = \"fast\"\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("missing field `kind`"), "{e}");
}

#[test]
fn missing_mesh_file_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("rig.toml");
    std::fs::write(dir.path().join("camera.json"), "{}").unwrap();
    std::fs::write(
        &cfg,
        "[source]\nkind = \"live\"\n[live]\nevent_camera = \"evk4\"\ndepth_camera = \"d435i\"\n\
         depth_device = \"/dev/video2\"\ncalibration = \"camera.json\"\n\
         [[objects]]\nname = \"mug\"\nmesh = \"objects/mug.obj\"\nposition = [0.0, 0.0, 0.6]\n\
         orientation = [0.0, 0.0, 0.0, 1.0]\n",
    )
    .unwrap();
    let e = load(&cfg).unwrap_err().to_string();
    assert!(e.contains("`objects[0].mesh`"), "{e}");
    assert!(
        e.contains("objects/mug.obj") && e.contains("does not exist"),
        "{e}"
    );
    // With the mesh there the configuration is accepted, paths resolved against its directory.
    std::fs::create_dir(dir.path().join("objects")).unwrap();
    std::fs::write(dir.path().join("objects/mug.obj"), "v 0 0 0\n").unwrap();
    let c = load(&cfg).unwrap();
    assert_eq!(c.objects[0].mesh, dir.path().join("objects/mug.obj"));
}

#[test]
fn bad_quaternion_is_refused() {
    let e = parse(
        "[source]\nkind = \"demo\"\n[[objects]]\nname = \"a\"\nmesh = \"a.obj\"\nposition = [0.0, 0.0, 1.0]\n\
         orientation = [0.0, 0.0, 0.0, 2.0]\n",
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("`objects[0].orientation`"), "{e}");
}

#[test]
fn key_lookup() {
    let t = "a = 1\n[x]\nb = 2\n[y.z]\nc = 3\n";
    assert_eq!(key_at(t, t.find("b =").unwrap()), (3, "x.b".into()));
    assert_eq!(key_at(t, t.find("c =").unwrap() + 4), (5, "y.z.c".into()));
    assert_eq!(key_at(t, 0), (1, "a".into()));
}

#[test]
fn shipped_configurations_load_and_the_rig_says_the_live_depth_camera_is_not_there_yet() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../config");
    let demo = load(&root.join("default.toml")).unwrap();
    assert_eq!(demo.source.kind, SourceKind::Demo);
    let ros2 = load(&root.join("rig-ros2.toml")).unwrap();
    assert_eq!(ros2.source.kind, SourceKind::Ros2);
    let mut quick = ros2.clone();
    let r = quick.ros2.as_mut().unwrap();
    // Nothing publishes here: the wait ends with what is missing, naming the topic and where it looked.
    r.wait_for_data_s = 0.3;
    r.connect = Vec::new();
    let e = crate::runtime::setup::build_source(&quick)
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("no EventPacket arrived on /event_camera/events"),
        "{e}"
    );
    let rig = load(&root.join("rig-evk4-d435i.toml")).unwrap();
    assert_eq!(rig.source.kind, SourceKind::Live);
    assert_eq!(rig.can.interface.as_deref(), Some("can0"));
    assert_eq!(rig.objects[0].name, "box");
    let e = crate::runtime::setup::build_source(&rig)
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("live D435i driver is not implemented yet"),
        "{e}"
    );
    let e = crate::runtime::setup::build_source(&demo)
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("eventtrack6d demo"), "{e}");
}

#[test]
fn tables_the_configuration_does_not_use_are_named() {
    let text = "[source]\nkind = \"replay\"\n[replay]\nrecording = \"r\"\n[demo]\nseed = 3\n\
                [sinks]\nzenoh = false\n[zenoh]\ndomain_id = 5\n[can]\nenabled = false\ninterface = \"can1\"\n";
    let c = parse(text).unwrap();
    let unused = unused_tables(&c, text);
    assert_eq!(
        unused,
        [
            "[demo] is not used: [source] kind is `replay`",
            "[zenoh] is not used: [sinks] zenoh is false",
            "[can] is not used: [can] enabled is false",
        ]
    );
    // The shipped files use what they set.
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../config");
    let mut checked = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            let text = std::fs::read_to_string(&path).unwrap();
            let c = parse(&text).unwrap();
            let unused = unused_tables(&c, &text);
            assert!(unused.is_empty(), "{}: {unused:?}", path.display());
            checked += 1;
        }
    }
    assert!(checked >= 2, "{checked} shipped configurations");
}

/// A TOML value of any type, in or out of range.
fn any_value() -> impl proptest::strategy::Strategy<Value = String> {
    use proptest::prelude::*;
    prop_oneof![
        any::<i64>().prop_map(|v| v.to_string()),
        (-1e6f64..1e6).prop_map(|v| format!("{v:?}")),
        Just("nan".to_string()),
        Just("-inf".to_string()),
        any::<bool>().prop_map(|v| v.to_string()),
        "[a-z0-9/._:-]{0,12}".prop_map(|s| format!("{s:?}")),
        Just("[]".to_string()),
        Just("[1, \"x\"]".to_string()),
        Just("{ a = 1 }".to_string()),
        Just("\"\"\"\nmulti\n\"\"\"".to_string()),
    ]
}

proptest::proptest! {
    /// The shipped defaults with values replaced, lines dropped or repeated, and random text mixed in: parsing
    /// never panics, and every refusal names where it came from.
    #[test]
    fn mutated_configurations_parse_or_name_the_file_and_key(
        edits in proptest::collection::vec((0usize..200, 0u8..4, any_value()), 0..6),
        noise in "[ -~\n]{0,40}",
    ) {
        let mut lines: Vec<String> = DEFAULT_CONFIG_TOML.lines().map(str::to_string).collect();
        for (at, what, value) in edits {
            let i = at % lines.len();
            match what {
                0 => {
                    if let Some((key, _)) = lines[i].split_once('=') {
                        lines[i] = format!("{key}= {value}");
                    }
                }
                1 => {
                    lines.remove(i);
                }
                2 => {
                    let repeated = lines[i].clone();
                    lines.insert(i, repeated);
                }
                _ => lines.insert(i, format!("extra_{i} = {value}")),
            }
        }
        lines.push(noise);
        match parse(&lines.join("\n")) {
            Ok(c) => {
                // What was accepted is what the file says (or the default where it says nothing).
                let doc: toml::Value = toml::from_str(&lines.join("\n")).expect("an accepted file is TOML");
                let int = |table: &str, key: &str| doc.get(table).and_then(|t| t.get(key)).and_then(toml::Value::as_integer);
                let text = |table: &str, key: &str| doc.get(table).and_then(|t| t.get(key)).and_then(toml::Value::as_str);
                proptest::prop_assert_eq!(
                    c.queue.event_batches as i64,
                    int("queue", "event_batches").unwrap_or(QueueConfig::default().event_batches as i64)
                );
                proptest::prop_assert_eq!(
                    c.status.period_ms as i64,
                    int("status", "period_ms").unwrap_or(StatusConfig::default().period_ms as i64)
                );
                let default_method = TrackerConfig::default().method;
                proptest::prop_assert_eq!(
                    c.tracker.method.as_str(),
                    text("tracker", "method").unwrap_or(default_method.as_str())
                );
            }
            Err(e) => {
                let message = e.to_string();
                proptest::prop_assert!(message.starts_with("test.toml: "), "{}", message);
                // A malformed or out-of-range value names its key (and a parse error its line).
                match &e {
                    ConfigError::Parse { line, key, .. } => {
                        proptest::prop_assert!(!key.is_empty() || *line > 0, "{}", message);
                    }
                    ConfigError::Invalid { key, .. } => {
                        proptest::prop_assert!(!key.is_empty(), "{}", message);
                    }
                    _ => proptest::prop_assert!(message.len() > "test.toml: ".len() + 5, "{}", message),
                }
            }
        }
    }
}

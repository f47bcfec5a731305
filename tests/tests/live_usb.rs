//! The live EVK4 path through a real kernel's USB stack: an emulated camera (`hil-sim usb-camera`) served over
//! USB/IP, attached by the guest kernel's `vhci-hcd` in a QEMU VM (tests/vm/), and `eventtrack6d run` with a live
//! configuration reading it with rusb through usbfs, exactly as on a robot PC: the poses of a run where nothing
//! is dropped, an unplug and re-plug, a burst above what the ring holds, a register that fails. The binaries are
//! the workspace's `target/debug` ones (`cargo test --workspace` builds them; `cargo build` first when running
//! this file alone). Skipped, with the reason printed, only where QEMU or the VM kernel is missing (`.ci/setup`
//! installs both).

#![allow(clippy::unwrap_used, clippy::expect_used)]

use eventtrack6d_tests::vm;
use hil_sim::generate::{GenerateConfig, ObjectSource, generate};
use hil_sim::motion::{MotionProfile, SpeedLevel};
use hil_sim::objects::ObjectKind;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Mutex;

/// One VM at a time: two TCG guests on two cores only slow each other down.
static VM: Mutex<()> = Mutex::new(());

/// A generated recording (the mug shaken slowly) of `seconds` in `dir`.
fn recording(dir: &Path, seconds: f64) -> PathBuf {
    let rec = dir.join("rec");
    let cfg = GenerateConfig::new(
        ObjectSource::Library(ObjectKind::Mug),
        MotionProfile::Shake,
        SpeedLevel::Slow,
        seconds,
        7,
    );
    generate(&cfg, &rec, |_| {}).unwrap();
    rec
}

/// What a guest run printed.
struct GuestRun {
    ok: bool,
    stdout: String,
    stderr: String,
}

impl GuestRun {
    fn poses(&self) -> Vec<&str> {
        rows(vm::section(&self.stdout, "poses.csv").unwrap_or(""))
    }
    fn camera(&self) -> serde_json::Value {
        serde_json::from_str(vm::section(&self.stdout, "camera.json").unwrap_or("null"))
            .unwrap_or_default()
    }
    /// The number before `label` on the summary's `usb:` line.
    fn usb(&self, label: &str) -> u64 {
        let line = self
            .stdout
            .lines()
            .find(|l| l.starts_with("usb:"))
            .unwrap_or_else(|| panic!("{}", self.all()));
        let at = line
            .find(label)
            .unwrap_or_else(|| panic!("no `{label}` in {line}"));
        line[..at]
            .split(|c: char| !c.is_ascii_digit())
            .rfind(|w| !w.is_empty())
            .unwrap()
            .parse()
            .unwrap()
    }
    fn all(&self) -> String {
        format!("stdout:\n{}\nstderr:\n{}", self.stdout, self.stderr)
    }
}

/// Runs the live tracker in the VM on the emulated camera streaming `rec`, for `seconds` of stream time, with
/// `live_extra` added to the `[live]` table, the emulator's `camera_args` and the guest script's `env`.
fn live_run(
    dir: &Path,
    rec: &Path,
    seconds: f64,
    live_extra: &str,
    camera_args: &[&str],
    env: &[&str],
) -> GuestRun {
    let config = dir.join("live.toml");
    let text = format!(
        "[source]\nkind = \"live\"\n[live]\nevent_camera = \"evk4\"\ndepth_camera = \"recording\"\n\
         depth_recording = \"{}\"\nreconnect_ms = 100\n{live_extra}\n[tracker]\ndefer_late_depth = false\n\
         [output]\ndir = \"/tmp/live-out\"\n[sinks]\ncsv = true\nzenoh = false\n[can]\nenabled = false\n",
        rec.display()
    );
    std::fs::write(&config, text).unwrap();
    let bin = vm::bin_dir();
    let seconds = seconds.to_string();
    let mut args: Vec<&str> = Vec::new();
    args.extend([
        "tests/vm/live-evk4.sh",
        bin.to_str().unwrap(),
        rec.to_str().unwrap(),
    ]);
    args.extend([config.to_str().unwrap(), seconds.as_str()]);
    args.extend(camera_args);
    let _one = VM.lock().unwrap_or_else(|p| p.into_inner());
    let out = vm::run(300, env, &args).unwrap();
    GuestRun {
        ok: out.status.success(),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}

/// A work directory for a VM test, or `None` (with the reason printed) where the VM cannot run.
fn vm_work_dir() -> Option<tempfile::TempDir> {
    if let Some(why) = vm::unavailable() {
        eprintln!("skipped: the VM cannot run here: {why}");
        return None;
    }
    Some(vm::work_dir().unwrap())
}

/// `eventtrack6d track` of `rec` on the host: the pose CSV.
fn track_offline(dir: &Path, rec: &Path) -> String {
    let csv = dir.join("offline.csv");
    let out = Command::new(vm::bin_dir().join("eventtrack6d"))
        .args([
            "track",
            rec.to_str().unwrap(),
            "--out",
            csv.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    std::fs::read_to_string(&csv).unwrap()
}

fn rows(csv: &str) -> Vec<&str> {
    csv.lines()
        .filter(|l| l.starts_with(|c: char| c.is_ascii_digit()))
        .collect()
}

fn t_us(row: &str) -> i64 {
    row.split(',').next().unwrap().parse().unwrap()
}

#[test]
fn a_live_run_through_the_kernel_usb_stack_publishes_the_offline_poses() {
    let Some(work) = vm_work_dir() else { return };
    let rec = recording(work.path(), 3.0);
    let offline_text = track_offline(work.path(), &rec);
    let run = live_run(
        work.path(),
        &rec,
        2.9,
        "ring_mib = 512",
        &["--pace", "fast"],
        &[],
    );
    assert!(run.ok, "{}", run.all());
    // The camera was found through the kernel, with the identity the emulator gave it.
    assert!(
        run.stdout.contains("EVK4 04b4:00f5") && run.stdout.contains("serial 00EE6D00"),
        "{}",
        run.all()
    );
    assert!(run.stdout.contains("usable: yes"), "{}", run.all());
    assert_eq!(run.usb("transfers dropped"), 0, "{}", run.all());
    let live = run.poses();
    let offline = rows(&offline_text);
    // Every tick within the live run's stream time, to the bit.
    let within = offline
        .iter()
        .filter(|r| t_us(r) < t_us(offline[0]) + 2_800_000)
        .count();
    assert!(
        live.len() >= within,
        "{} live poses, {within} offline within 2.8 s:\n{}",
        live.len(),
        run.all()
    );
    assert_eq!(
        live[..],
        offline[..live.len()],
        "the live run's poses differ from track's"
    );
}

#[test]
fn an_unplugged_camera_is_reported_published_through_reopened_and_tracked_again() {
    let Some(work) = vm_work_dir() else { return };
    let rec = recording(work.path(), 3.0);
    // The run ends two seconds after the camera has sent everything (Ctrl-C), however long the outage took.
    let run = live_run(
        work.path(),
        &rec,
        1000.0,
        "ring_mib = 512",
        &["--pace", "fast", "--unplug-after", "0.5"],
        &["REPLUG=1", "STOP_WHEN_FINISHED=1"],
    );
    assert!(run.ok, "{}", run.all());
    // Reported at once: the stream time it happened at, and how long after the camera's last data.
    let report = run
        .stderr
        .lines()
        .find(|l| l.contains("was disconnected (stream time"))
        .unwrap_or_else(|| panic!("no disconnect report:\n{}", run.all()));
    let silent_ms: f64 = report
        .split(", ")
        .nth(1)
        .and_then(|s| s.split(" ms").next())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("{report}"));
    assert!(
        silent_ms <= 100.0,
        "reported {silent_ms} ms after the last data: {report}"
    );
    assert_eq!(run.usb("outage(s)"), 1, "{}", run.all());
    assert_eq!(run.usb("session(s)"), 2, "{}", run.all());
    assert_eq!(run.camera()["unplugs"], 1, "{}", run.all());
    let unplugged_us = (report
        .split("stream time ")
        .nth(1)
        .and_then(|s| s.split(' ').next())
        .and_then(|s| s.parse::<f64>().ok())
        .unwrap()
        * 1e6) as i64;
    // While the camera was away (at least the 0.5 s before the re-plug and the 2.5 s bring-up), the tick pulses
    // went on on the wall clock and every tick published the object, as `lost` (no measurement is there).
    assert!(run.usb("tick pulses made") >= 100, "{}", run.all());
    let poses = run.poses();
    let during: Vec<&&str> = poses
        .iter()
        .filter(|r| (unplugged_us + 200_000..unplugged_us + 2_000_000).contains(&t_us(r)))
        .collect();
    assert!(
        during.len() >= 200,
        "{} poses in the 1.8 s after the unplug:\n{}",
        during.len(),
        run.all()
    );
    assert!(during.iter().all(|r| r.ends_with(",0,lost")), "{during:?}");
    // Tracking resumed on the camera's return: its stream continues after the pulses made meanwhile, and the
    // tracker's own states are published again.
    let last = t_us(poses.last().unwrap());
    assert!(!poses.last().unwrap().ends_with(",0,lost"), "{}", run.all());
    assert!(
        last > unplugged_us + 3_000_000,
        "last pose at {last} us, unplugged at {unplugged_us} us:\n{}",
        run.all()
    );
}

#[test]
fn a_burst_the_ring_cannot_hold_is_dropped_counted_and_resynchronised() {
    let Some(work) = vm_work_dir() else { return };
    let rec = recording(work.path(), 1.0);
    // Dropped data may take the end of the recording with it, so the run ends two seconds after the camera has
    // sent everything (Ctrl-C), not at a stream time it may never see.
    let run = live_run(
        work.path(),
        &rec,
        1000.0,
        "ring_mib = 1\nusb_transfer_kib = 64",
        &[
            "--pace",
            "realtime",
            "--burst-after",
            "0.2",
            "--burst-mib",
            "16",
        ],
        &["STOP_WHEN_FINISHED=1"],
    );
    assert!(run.ok, "{}", run.all());
    let sent = run.camera()["camera"]["bytes_sent"].as_u64().unwrap();
    let received = run.usb("bytes received");
    let dropped = run.usb("transfers dropped (");
    let dropped_bytes = run.usb(" bytes; ring");
    assert!(dropped > 0 && dropped_bytes > 0, "{}", run.all());
    assert_eq!(
        sent,
        received + dropped_bytes,
        "every byte the camera sent is received or counted as dropped\n{}",
        run.all()
    );
    assert!(run.usb("gaps resynchronised") >= 1, "{}", run.all());
    assert!(!run.poses().is_empty(), "{}", run.all());
}

#[test]
fn a_recorded_session_replays_to_the_offline_poses_of_what_the_camera_saw() {
    let Some(work) = vm_work_dir() else { return };
    let rec = recording(work.path(), 1.0);
    let offline_text = track_offline(work.path(), &rec);
    let run = live_run(
        work.path(),
        &rec,
        0.9,
        "ring_mib = 256",
        &["--pace", "fast"],
        &["MODE=record"],
    );
    assert!(run.ok, "{}", run.all());
    assert!(
        run.stdout.contains("0 transfers dropped (0 bytes)"),
        "{}",
        run.all()
    );
    let recorded = run.poses();
    let offline = rows(&offline_text);
    assert!(
        recorded.len() >= 100,
        "{} poses from the recorded session:\n{}",
        recorded.len(),
        run.all()
    );
    assert_eq!(
        recorded[..],
        offline[..recorded.len()],
        "the recorded session tracks differently"
    );
}

#[test]
fn a_stalled_camera_delays_the_stream_but_changes_no_pose() {
    let Some(work) = vm_work_dir() else { return };
    let rec = recording(work.path(), 1.0);
    let offline_text = track_offline(work.path(), &rec);
    let camera = [
        "--pace",
        "fast",
        "--stall-after",
        "0.3",
        "--stall-ms",
        "400",
    ];
    let run = live_run(work.path(), &rec, 0.9, "ring_mib = 256", &camera, &[]);
    assert!(run.ok, "{}", run.all());
    // The bulk-IN requests waited 400 ms with no data: not an outage, nothing dropped, the same poses.
    assert_eq!(run.usb("outage(s)"), 0, "{}", run.all());
    assert_eq!(run.usb("transfers dropped"), 0, "{}", run.all());
    let live = run.poses();
    let offline = rows(&offline_text);
    assert!(live.len() >= 100, "{}", run.all());
    assert_eq!(live[..], offline[..live.len()], "a stall changed the poses");
}

#[test]
fn malformed_words_from_the_camera_are_skipped_and_counted() {
    let Some(work) = vm_work_dir() else { return };
    let rec = recording(work.path(), 0.5);
    let camera = ["--pace", "fast", "--malformed-every", "5000"];
    let run = live_run(work.path(), &rec, 0.4, "ring_mib = 256", &camera, &[]);
    assert!(run.ok, "{}", run.all());
    let skipped: u64 = run
        .stdout
        .lines()
        .find_map(|l| l.strip_prefix("decode anomalies: unknown_type "))
        .and_then(|n| n.split(',').next()?.trim().parse().ok())
        .unwrap_or_else(|| panic!("no decode anomalies line:\n{}", run.all()));
    let injected = run.camera()["camera"]["malformed_sent"].as_u64().unwrap();
    // Every malformed word the decoder saw is counted; the ones still on the way when the run ended are not.
    assert!(
        skipped > 0 && skipped <= injected,
        "{skipped} skipped of {injected} injected\n{}",
        run.all()
    );
    assert!(run.poses().len() >= 40, "{}", run.all());
}

#[test]
fn a_failing_register_write_stops_the_run_naming_the_register() {
    let Some(work) = vm_work_dir() else { return };
    let rec = recording(work.path(), 0.3);
    let run = live_run(
        work.path(),
        &rec,
        0.2,
        "",
        &["--fail-register", "0x1014"],
        &[],
    );
    assert!(!run.ok, "{}", run.all());
    assert!(
        run.stderr.contains("register 0x1014 (bias) = 0x11a1504d"),
        "{}",
        run.all()
    );
    assert!(
        run.stderr.contains("refused property 0x40010102 (errno 5)"),
        "{}",
        run.all()
    );
}

//! The live EVK4 path through a real kernel's USB stack: an emulated camera (`hil-sim usb-camera`) served over
//! USB/IP, attached by the guest kernel's `vhci-hcd` in a QEMU VM (tests/vm/), and `eventtrack6d run` with a live
//! configuration reading it with rusb through usbfs, exactly as on a robot PC. Nothing is dropped on the way, so
//! the live run publishes `eventtrack6d track`'s poses of the same recording, bit for bit. Skipped, with the
//! reason printed, only where QEMU or the VM kernel is missing (`.ci/setup` installs both).

#![allow(clippy::unwrap_used, clippy::expect_used)]

use eventtrack6d_tests::vm;
use hil_sim::generate::{GenerateConfig, ObjectSource, generate};
use hil_sim::motion::{MotionProfile, SpeedLevel};
use hil_sim::objects::ObjectKind;
use std::path::Path;
use std::process::Command;

/// Stream time the live run covers, seconds (the recording is 3 s; the run ends at its first event plus this).
const LIVE_SECONDS: f64 = 2.9;

/// Writes a live configuration reading the EVK4, with depth from `rec`, its poses to the guest's /tmp/live-out.
fn live_config(dir: &Path, rec: &Path) -> std::path::PathBuf {
    let path = dir.join("live.toml");
    let text = format!(
        "[source]\nkind = \"live\"\n[live]\nevent_camera = \"evk4\"\ndepth_camera = \"recording\"\n\
         depth_recording = \"{}\"\nring_mib = 512\n[tracker]\ndefer_late_depth = false\n[output]\n\
         dir = \"/tmp/live-out\"\n[sinks]\ncsv = true\nzenoh = false\n[can]\nenabled = false\n",
        rec.display()
    );
    std::fs::write(&path, text).unwrap();
    path
}

fn rows(csv: &str) -> Vec<&str> {
    csv.lines()
        .filter(|l| l.starts_with(|c: char| c.is_ascii_digit()))
        .collect()
}

#[test]
fn a_live_run_through_the_kernel_usb_stack_publishes_the_offline_poses() {
    if let Some(why) = vm::unavailable() {
        eprintln!("skipped: the VM cannot run here: {why}");
        return;
    }
    let work = vm::work_dir().unwrap();
    let rec = work.path().join("rec");
    let cfg = GenerateConfig::new(
        ObjectSource::Library(ObjectKind::Mug),
        MotionProfile::Shake,
        SpeedLevel::Slow,
        3.0,
        7,
    );
    generate(&cfg, &rec, |_| {}).unwrap();
    let bin = vm::bin_dir();
    let offline_csv = work.path().join("offline.csv");
    let offline = Command::new(bin.join("eventtrack6d"))
        .args([
            "track",
            rec.to_str().unwrap(),
            "--out",
            offline_csv.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(
        offline.status.success(),
        "{}",
        String::from_utf8_lossy(&offline.stderr)
    );
    let config = live_config(work.path(), &rec);
    let out = vm::run(
        600,
        &[
            "tests/vm/live-evk4.sh",
            bin.to_str().unwrap(),
            rec.to_str().unwrap(),
            config.to_str().unwrap(),
            &LIVE_SECONDS.to_string(),
            "--pace",
            "fast",
        ],
    )
    .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "VM run failed ({:?}):\n{stdout}\n{stderr}",
        out.status
    );
    // The camera was found through the kernel, with the identity the emulator gave it.
    assert!(
        stdout.contains("EVK4 04b4:00f5")
            && stdout.contains("serial 00EE6D00")
            && stdout.contains("usable: yes"),
        "{stdout}"
    );
    assert!(stdout.contains(" 0 transfers dropped"), "{stdout}");
    let live = rows(vm::section(&stdout, "poses.csv").unwrap());
    let offline_text = std::fs::read_to_string(&offline_csv).unwrap();
    let offline = rows(&offline_text);
    // Every tick within the live run's stream time, to the bit.
    let first_t: i64 = offline[0].split(',').next().unwrap().parse().unwrap();
    let within = offline
        .iter()
        .filter(|r| r.split(',').next().unwrap().parse::<i64>().unwrap() < first_t + 2_800_000)
        .count();
    assert!(
        live.len() >= within,
        "{} live poses, {within} offline within 2.8 s:\n{stdout}\n{stderr}",
        live.len()
    );
    assert_eq!(
        live[..],
        offline[..live.len()],
        "the live run's poses differ from track's"
    );
}

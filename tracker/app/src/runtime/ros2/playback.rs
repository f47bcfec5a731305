//! The configuration that tracks a recording played over ROS 2 (`hil-sim ros2-play`): the ROS 2 source with the
//! recording's calibration and trigger schedule, and its ground-truth objects at their poses at the first tick,
//! as `[[objects]]` (what a user of a real rig writes from a known placement).

use crate::runtime::error::RuntimeError;
use crate::runtime::setup::recording_scene;
use drivers::recording::Recording;
use std::fmt::Write as _;

/// Where the tracker's ROS 2 session connects and listens.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct PlaybackEndpoints {
    /// `[ros2] connect`.
    pub connect: Vec<String>,
    /// `[ros2] listen`.
    pub listen: Vec<String>,
}

fn toml_string(s: &str) -> String {
    // A TOML basic string: quotes and backslashes escaped (paths and names have nothing else to escape).
    format!("\"{}\"", s.replace('\\', "\\\\").replace('"', "\\\""))
}

fn toml_list(v: &[String]) -> String {
    let items: Vec<String> = v.iter().map(|s| toml_string(s)).collect();
    format!("[{}]", items.join(", "))
}

/// The TOML configuration that runs the tracker on `rec` (directory `rec.dir()`) played over ROS 2; the pose
/// CSV goes to `out_dir`, zenoh publishing is on. The run ends 2 s after the last event packet.
pub fn playback_config(
    rec: &Recording,
    endpoints: &PlaybackEndpoints,
    out_dir: &std::path::Path,
) -> Result<String, RuntimeError> {
    let scene = recording_scene(rec, &[])?;
    let s = rec.meta.trigger;
    let dir = rec.dir();
    let mut t = String::new();
    let path = |p: std::path::PathBuf| toml_string(&p.display().to_string());
    // Writing into a String cannot fail.
    let _ = writeln!(
        t,
        "# The tracker on {} played over ROS 2 (`hil-sim ros2-play`): written by `eventtrack6d ros2-config`.\n\
         [source]\nkind = \"ros2\"\n\n[ros2]\ncalibration = {}\nconnect = {}\nlisten = {}\ntrigger_channel = {}\n\
         tick_rate_hz = {:?}\nticks_per_depth = {}\nnarrow_width_us = {}\nwide_width_us = {}\nwait_for_data_s = 60\n\
         end_after_idle_s = 2\n\n[output]\ndir = {}\n\n[sinks]\ncsv = true\nzenoh = true\n\n[can]\nenabled = false",
        dir.display(),
        path(dir.join("camera.json")),
        toml_list(&endpoints.connect),
        toml_list(&endpoints.listen),
        s.channel,
        s.tick_rate_hz,
        s.ticks_per_depth,
        s.narrow_width_us,
        s.wide_width_us,
        path(out_dir.to_path_buf()),
    );
    for o in &scene.objects {
        let p = o.first_pose.1.translation.vector;
        let q = o.first_pose.1.rotation.coords;
        let _ = writeln!(
            t,
            "\n[[objects]]\nname = {}\nmesh = {}\nposition = [{:?}, {:?}, {:?}]\norientation = [{:?}, {:?}, {:?}, {:?}]\n\
             models_info = {}",
            toml_string(&o.name),
            path(o.mesh.clone()),
            p.x,
            p.y,
            p.z,
            q.x,
            q.y,
            q.z,
            q.w,
            path(dir.join("models").join("models_info.json")),
        );
    }
    Ok(t)
}

//! The network sinks of a configuration: zenoh / ROS 2 (poses, status, liveliness) and CAN (candump log,
//! SocketCAN).

use super::config::Config;
use super::control::ControlApplier;
use super::error::RuntimeError;
use super::setup::{OutputPaths, TrackerScene};
use crate::publish::SharedSink;
use crate::publish::control::control_channel;
use crate::publish::zenoh::{ObjectOutput, ZenohPosePublisher};
use crate::publish::{PoseSink, PublishError};
use scene::mesh::{MeshLoadOptions, load_obj};
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

/// Puts a status document (JSON bytes) somewhere (the zenoh status key).
pub type StatusPut = Box<dyn FnMut(&[u8]) -> Result<(), PublishError> + Send>;

/// The network sinks of a run.
#[derive(Default)]
pub struct NetworkSinks {
    /// Pose sinks, in publishing order (zenoh first: it is the latency-critical one).
    pub sinks: Vec<Box<dyn PoseSink>>,
    /// Where the status document goes (the zenoh status key), when zenoh is on.
    pub status: Option<StatusPut>,
    /// The candump log, when on.
    pub candump: Option<PathBuf>,
    /// The tracker thread's side of the control commands the zenoh sink receives, when control is on.
    pub control: Option<ControlApplier>,
}

/// Builds the zenoh and CAN sinks the configuration turns on. A zenoh session that cannot open is an error (the
/// configuration asked for it); `runtime` runs the SocketCAN writer task.
pub fn build_network_sinks(
    config: &Config,
    scene: &TrackerScene,
    _outputs: &OutputPaths,
    runtime: &tokio::runtime::Handle,
) -> Result<NetworkSinks, RuntimeError> {
    let mut out = NetworkSinks::default();
    let objects: Vec<String> = scene.objects.iter().map(|o| o.name.clone()).collect();
    let objects = objects.as_slice();
    if config.sinks.zenoh {
        let outputs = object_outputs(scene);
        let (sender, inbox) = control_channel();
        let control = config.zenoh.control.then_some(sender);
        // Stamps are the event camera's clock (offset 0): replayed and live poses carry their own time base.
        let ros_time_offset_ns = 0;
        if control.is_some() {
            out.control = Some(ControlApplier::new(
                inbox,
                scene.objects.iter().map(|o| o.first_pose.1).collect(),
                ros_time_offset_ns,
                config.zenoh.control_max_age_ms,
            ));
        }
        let publisher =
            ZenohPosePublisher::with_outputs(&config.zenoh, &outputs, ros_time_offset_ns, control)
                .map_err(|e| {
                    RuntimeError::Sink(PublishError::Transport {
                        sink: "zenoh".into(),
                        message: e.to_string(),
                    })
                })?;
        let shared = Arc::new(Mutex::new(publisher));
        out.sinks.push(Box::new(SharedSink::new(shared.clone())));
        out.status = Some(Box::new(move |json: &[u8]| {
            let mut publisher = shared.lock().unwrap_or_else(|p| p.into_inner());
            let doc = with_pose_queries(json, publisher.pose_query_counts());
            publisher.put_status(&doc)
        }));
    }
    if config.can.enabled {
        let mut can = config.can.clone();
        if let Some(log) = &mut can.candump_log
            && log.is_relative()
        {
            *log = config.output.dir.join(&*log);
        }
        can.validate(objects.len()).map_err(|e| {
            RuntimeError::Sink(PublishError::Transport {
                sink: "can".into(),
                message: e.to_string(),
            })
        })?;
        let (sinks, errors) = can.build_sinks(runtime);
        // A missing CAN interface (or an unwritable log) is reported and the other sinks carry on.
        for e in errors {
            eprintln!("warning: {e}");
        }
        out.candump = can.candump_log.clone().filter(|p| {
            let name = format!("candump:{}", p.display());
            sinks.iter().any(|s| s.name() == name)
        });
        out.sinks.extend(sinks);
    }
    Ok(out)
}

/// The objects as the zenoh outputs describe them: names and their meshes' bounds (zero-sized when a mesh does not
/// load here; the tracker, which loaded it, reports that).
fn object_outputs(scene: &TrackerScene) -> Vec<ObjectOutput> {
    scene
        .objects
        .iter()
        .map(|o| {
            let mut out = ObjectOutput::named(&o.name);
            if let Ok(loaded) = load_obj(&o.mesh, &MeshLoadOptions::default()) {
                let b = loaded.mesh.aabb();
                out.bounds = (
                    [b.min.x, b.min.y, b.min.z].map(f64::from),
                    [b.max.x, b.max.y, b.max.z].map(f64::from),
                );
            }
            out
        })
        .collect()
}

/// The status document `json` with the zenoh sink's pose queries so far, `pose_queries: {answered, refused}`,
/// added at its top level; `json` unchanged if it is not a JSON object.
fn with_pose_queries(json: &[u8], (answered, refused): (u64, u64)) -> Vec<u8> {
    match serde_json::from_slice::<serde_json::Value>(json) {
        Ok(serde_json::Value::Object(mut doc)) => {
            doc.insert(
                "pose_queries".into(),
                serde_json::json!({ "answered": answered, "refused": refused }),
            );
            serde_json::to_vec(&doc).unwrap_or_else(|_| json.to_vec())
        }
        _ => json.to_vec(),
    }
}

#[cfg(test)]
mod tests {
    use super::with_pose_queries;

    #[test]
    fn the_status_gets_the_pose_query_counts() {
        let doc = with_pose_queries(br#"{"state":"running","ticks":3}"#, (5, 2));
        let v: serde_json::Value = serde_json::from_slice(&doc).unwrap();
        assert_eq!(v["state"], "running");
        assert_eq!(v["ticks"], 3);
        assert_eq!(v["pose_queries"]["answered"], 5);
        assert_eq!(v["pose_queries"]["refused"], 2);
        assert_eq!(with_pose_queries(b"[1,2]", (1, 1)), b"[1,2]");
        assert_eq!(with_pose_queries(b"not json", (1, 1)), b"not json");
    }
}

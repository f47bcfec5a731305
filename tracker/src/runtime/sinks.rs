//! The network sinks of a configuration: zenoh / ROS 2 (poses, status, liveliness) and CAN (candump log,
//! SocketCAN).

use super::config::Config;
use super::setup::OutputPaths;
use super::{RuntimeError, StatusPut};
use crate::publish::PoseSink;
use std::path::PathBuf;

/// The network sinks of a run.
#[derive(Default)]
pub struct NetworkSinks {
    /// Pose sinks, in publishing order (zenoh first: it is the latency-critical one).
    pub sinks: Vec<Box<dyn PoseSink>>,
    /// Where the status document goes (the zenoh status key), when zenoh is on.
    pub status: Option<StatusPut>,
    /// The candump log, when on.
    pub candump: Option<PathBuf>,
}

/// Builds the zenoh and CAN sinks the configuration turns on.
pub fn build_network_sinks(
    config: &Config,
    _objects: &[String],
    _outputs: &OutputPaths,
) -> Result<NetworkSinks, RuntimeError> {
    let out = NetworkSinks::default();
    if config.sinks.zenoh {
        eprintln!(
            "warning: zenoh publishing is not in this build yet; poses go to the other sinks"
        );
    }
    if config.sinks.candump || config.sinks.socketcan {
        eprintln!("warning: CAN publishing is not in this build yet; poses go to the other sinks");
    }
    Ok(out)
}

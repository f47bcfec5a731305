//! CAN / CAN FD publishing: the EventTrack6D pose frame layout (`config/can/eventtrack6d.dbc`, `docs/can.md`) and
//! sinks for SocketCAN, candump log files and memory.
//!
//! - [`layout`]: pure encoders/decoders, CRC-8/AUTOSAR, the classic-frame [`layout::Assembler`].
//! - [`candump`]: candump log writer/parser and [`CandumpSink`].
//! - [`socket`]: [`SocketCanSink`] (tokio writer task, bounded drop-oldest queue, reopen with backoff).
//! - [`memory`]: [`MemorySink`] for tests.
//! - [`dbc`]: generates the DBC text for a base identifier.

pub mod candump;
pub mod dbc;
pub mod layout;
pub mod memory;
pub mod socket;

#[cfg(test)]
mod tests;

pub use candump::{CandumpClock, CandumpSink};
pub use layout::{
    Assembler, CanFrame, DecodeError, DecodedPose, EncodeError, PoseEncoder, PoseFields,
};
pub use memory::{MemoryFrames, MemorySink};
pub use socket::{SocketCanSink, SocketHealth};

use crate::publish::PoseSink;
use std::path::PathBuf;

/// Why a CAN sink could not be created or configured.
#[derive(Debug, thiserror::Error)]
pub enum CanError {
    /// The configured interface is not there (e.g. no CAN hardware, or `vcan0` not created).
    #[error(
        "CAN interface `{iface}` does not exist (no such network device); SocketCAN publishing is off and the other \
         sinks carry on"
    )]
    NoSuchInterface {
        /// Interface name.
        iface: String,
    },
    /// The kernel has no SocketCAN support.
    #[error(
        "cannot open CAN interface `{iface}`: the kernel has no CAN socket support ({source}); SocketCAN publishing \
         is off and the other sinks carry on"
    )]
    NoCanSupport {
        /// Interface name.
        iface: String,
        /// The OS error.
        source: std::io::Error,
    },
    /// Opening the socket failed for another reason (permissions, interface down ...).
    #[error(
        "cannot open CAN interface `{iface}`: {source}; SocketCAN publishing is off and the other sinks carry on"
    )]
    Open {
        /// Interface name.
        iface: String,
        /// The OS error.
        source: std::io::Error,
    },
    /// The candump log file could not be created.
    #[error("cannot create candump log `{}`: {source}", path.display())]
    LogFile {
        /// Log path.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// A configuration value is invalid.
    #[error("invalid configuration `can.{key}`: {message}")]
    Config {
        /// Key under `[can]`.
        key: &'static str,
        /// What is wrong.
        message: String,
    },
}

/// The `[can]` section of the runtime configuration.
///
/// ```toml
/// [can]
/// enabled = true            # default true
/// interface = "can0"        # SocketCAN interface; default: none (no SocketCAN sink)
/// fd = false                # CAN FD (one 48-byte frame per pose) instead of 4 classic frames; default false
/// base_id = 0x300           # first identifier; the layout uses base_id .. base_id + 0x4F; default 0x300
/// candump_log = "out/can.log"  # also write frames to a candump log file; default: none
/// queue_len = 64            # SocketCAN queue, in poses (drop-oldest when full); default 64
/// ```
#[derive(
    Debug, Clone, PartialEq, Eq, serde::Deserialize, serde::Serialize, schemars::JsonSchema,
)]
#[serde(deny_unknown_fields, default)]
pub struct CanConfig {
    /// Publish on CAN at all (default `true`; nothing is created unless `interface` or `candump_log` is set).
    pub enabled: bool,
    /// SocketCAN interface name (`can0`, `vcan0`); `None` (default): no SocketCAN sink.
    pub interface: Option<String>,
    /// CAN FD: one 48-byte frame per pose (default `false`: four classic 8-byte frames).
    pub fd: bool,
    /// Base identifier (11-bit, at most [`layout::MAX_BASE_ID`]; default [`layout::DEFAULT_BASE_ID`] = 0x300).
    pub base_id: u16,
    /// candump log file to write the same frames to; `None` (default): no log.
    pub candump_log: Option<PathBuf>,
    /// SocketCAN queue length in poses (default 64, at least 1); when full the oldest pose is dropped and counted.
    pub queue_len: usize,
}

impl Default for CanConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            interface: None,
            fd: false,
            base_id: layout::DEFAULT_BASE_ID,
            candump_log: None,
            queue_len: 64,
        }
    }
}

impl CanConfig {
    /// The encoder this configuration implies.
    pub fn encoder(&self) -> PoseEncoder {
        PoseEncoder {
            base_id: self.base_id,
            fd: self.fd,
        }
    }

    /// Checks values against the layout for `objects` tracked objects; errors name the key.
    pub fn validate(&self, objects: usize) -> Result<(), CanError> {
        if self.base_id > layout::MAX_BASE_ID {
            return Err(CanError::Config {
                key: "base_id",
                message: format!(
                    "{:#X} is too large: the layout uses identifiers base_id..base_id+{:#X}, which must stay 11-bit \
                     (base_id at most {:#X})",
                    self.base_id,
                    layout::ID_SPAN - 1,
                    layout::MAX_BASE_ID
                ),
            });
        }
        if self.enabled && objects > layout::MAX_OBJECTS {
            return Err(CanError::Config {
                key: "enabled",
                message: format!(
                    "{objects} objects are tracked but the CAN layout carries at most {}",
                    layout::MAX_OBJECTS
                ),
            });
        }
        if self.queue_len == 0 {
            return Err(CanError::Config {
                key: "queue_len",
                message: "must be at least 1".into(),
            });
        }
        if let Some(iface) = &self.interface
            && (iface.is_empty() || iface.len() > 15 || iface.contains(['/', ' ']))
        {
            return Err(CanError::Config {
                key: "interface",
                message: format!(
                    "`{iface}` is not a network interface name (1 to 15 characters, no `/` or space)"
                ),
            });
        }
        Ok(())
    }

    /// Creates the configured sinks. Sinks that cannot be created are returned as errors for the caller to report;
    /// the others are usable (a missing CAN interface must not stop the process). `runtime` runs the SocketCAN
    /// writer task.
    pub fn build_sinks(
        &self,
        runtime: &tokio::runtime::Handle,
    ) -> (Vec<Box<dyn PoseSink>>, Vec<CanError>) {
        let mut sinks: Vec<Box<dyn PoseSink>> = Vec::new();
        let mut errors = Vec::new();
        if !self.enabled {
            return (sinks, errors);
        }
        if let Some(path) = &self.candump_log {
            let iface = self.interface.as_deref().unwrap_or("can0");
            match CandumpSink::create(path, iface, self.encoder()) {
                Ok(s) => sinks.push(Box::new(s)),
                Err(e) => errors.push(e),
            }
        }
        if let Some(iface) = &self.interface {
            match SocketCanSink::open(iface, self.encoder(), self.queue_len, runtime) {
                Ok(s) => sinks.push(Box::new(s)),
                Err(e) => errors.push(e),
            }
        }
        (sinks, errors)
    }
}

//! The command line of `hil-sim usb-camera`.

use super::UsbCameraOptions;
use super::playback::{Pace, StreamFaults};
use std::net::SocketAddr;
use std::path::PathBuf;
use std::time::Duration;
use usbip::descriptors::Speed;

/// Serve an emulated Prophesee EVK4 over USB/IP, streaming a recording's events.
///
/// The camera presents the EVK4's descriptors (04b4:00f5, vendor interface 0, bulk endpoints 0x81 data, 0x02 and
/// 0x82 control), answers the Treuzell control protocol from an IMX636 register file that refuses what the sensor
/// would (a start before its initialisation, with the register named), and once the driver has started the
/// sensor streams RECORDING/events.raw (EVT 3.0 with trigger words; the trigger words only while the driver has
/// enabled the trigger input). A Linux host attaches it with `usbip attach -r HOST -b BUSID` (or by writing to
/// vhci-hcd's attach file), and the live driver then opens it through the kernel's USB stack like a real camera.
/// Bulk-IN requests wait until there is data; an unlink is answered as the kernel expects. Fault modes inject an
/// unplug, a stall, a burst above the link's bandwidth, malformed words and a failing register. The facts:
/// docs/live-camera.md.
#[derive(Debug, clap::Args)]
pub struct UsbCameraArgs {
    /// Recording directory whose events.raw is streamed (EVT 3.0).
    #[arg(value_name = "RECORDING")]
    pub recording: PathBuf,
    /// Address to listen on (USB/IP's port is 3240).
    #[arg(long, value_name = "ADDR", default_value = "127.0.0.1:3240")]
    pub listen: SocketAddr,
    /// Bus id the host imports the camera by.
    #[arg(long, value_name = "ID", default_value = "1-1")]
    pub busid: String,
    /// Link speed presented to the host: super (USB 3, the EVK4's) or high (USB 2).
    #[arg(long, value_name = "SPEED", default_value = "super", value_parser = ["super", "high"])]
    pub speed: String,
    /// Stream at the recording's real-time pace from the sensor's start, or as fast as the host reads.
    #[arg(long, value_name = "PACE", default_value = "realtime", value_parser = ["realtime", "fast"])]
    pub pace: String,
    /// The camera's serial number (hex).
    #[arg(long, value_name = "HEX", default_value = "00EE6D00")]
    pub serial: String,
    /// Fault: close the host's socket (an unplug) once, this many seconds after the host has started the sensor
    /// (read the answer to the start sequence's last write).
    #[arg(long, value_name = "S")]
    pub unplug_after: Option<f64>,
    /// Fault: hold the data back for --stall-ms once, after this many seconds of streaming.
    #[arg(long, value_name = "S")]
    pub stall_after: Option<f64>,
    /// Length of the stall, milliseconds.
    #[arg(long, value_name = "MS", default_value_t = 200)]
    pub stall_ms: u64,
    /// Fault: release --burst-mib of the stream at once, after this many seconds of streaming (real-time pace).
    #[arg(long, value_name = "S")]
    pub burst_after: Option<f64>,
    /// Size of the burst, MiB.
    #[arg(long, value_name = "MIB", default_value_t = 64.0)]
    pub burst_mib: f64,
    /// Fault: replace every N-th word with a word of a reserved type (the decoder skips and counts it).
    #[arg(long, value_name = "N")]
    pub malformed_every: Option<usize>,
    /// Fault: every write to this register (hex, e.g. 0x1014) fails, as a register that does not answer.
    #[arg(long, value_name = "ADDR")]
    pub fail_register: Option<String>,
    /// Write the camera's statistics (JSON: bytes sent, refused writes, sessions, unplugs) here every 100 ms.
    #[arg(long, value_name = "FILE")]
    pub stats: Option<PathBuf>,
}

fn seconds(name: &str, s: Option<f64>) -> anyhow::Result<Option<Duration>> {
    s.map(|s| {
        Duration::try_from_secs_f64(s)
            .map_err(|_| anyhow::anyhow!("--{name} {s}: not a duration in seconds"))
    })
    .transpose()
}

fn hex(name: &str, text: &str) -> anyhow::Result<u64> {
    u64::from_str_radix(text.trim_start_matches("0x").trim_start_matches("0X"), 16)
        .map_err(|_| anyhow::anyhow!("--{name} `{text}`: not a hexadecimal number"))
}

impl UsbCameraArgs {
    /// The options these arguments ask for, or an error naming the bad argument.
    pub fn options(&self) -> anyhow::Result<UsbCameraOptions> {
        let burst_bytes = self.burst_mib * 1024.0 * 1024.0;
        if !(0.0..1e12).contains(&burst_bytes) {
            anyhow::bail!("--burst-mib {}: not a size in MiB", self.burst_mib);
        }
        let fail_register = self
            .fail_register
            .as_deref()
            .map(|r| {
                hex("fail-register", r).and_then(|v| {
                    u32::try_from(v)
                        .map_err(|_| anyhow::anyhow!("--fail-register {r}: not a 32-bit address"))
                })
            })
            .transpose()?;
        Ok(UsbCameraOptions {
            recording: self.recording.clone(),
            listen: self.listen,
            busid: self.busid.clone(),
            speed: if self.speed == "high" {
                Speed::High
            } else {
                Speed::Super
            },
            pace: if self.pace == "fast" {
                Pace::Fast
            } else {
                Pace::Realtime
            },
            serial: hex("serial", &self.serial)?,
            unplug_after: seconds("unplug-after", self.unplug_after)?,
            faults: StreamFaults {
                stall_after: seconds("stall-after", self.stall_after)?,
                stall: Duration::from_millis(self.stall_ms),
                burst_after: seconds("burst-after", self.burst_after)?,
                burst_bytes: burst_bytes as usize,
                malformed_every: self.malformed_every.unwrap_or(0),
            },
            fail_register,
            stats: self.stats.clone(),
        })
    }
}

//! `hil-sim usb-camera`: an EVK4 that does not exist, served over USB/IP so a Linux host's `vhci-hcd` attaches it
//! as a real USB device, and the live driver talks to it through the kernel exactly as to a camera.
//!
//! [`device`] is the USB device (descriptors, EP0, the Treuzell control endpoints, the data endpoint),
//! [`control`] answers the control protocol from [`sensor`]'s register file (which refuses what the IMX636
//! would), and [`playback`] streams a recording's EVT 3.0 bytes at its pace with the stream faults injected.

pub mod args;
pub mod control;
pub mod device;
pub mod playback;
pub mod sensor;

use control::CameraIdentity;
use device::{CameraStats, Evk4Device};
use playback::{EventStream, Pace, Playback, StreamFaults};
use std::net::{SocketAddr, TcpListener};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};
use usbip::descriptors::{DeviceDescriptors, Speed};
use usbip::protocol::BusId;
use usbip::server::{self, ServerConfig};

/// Everything `hil-sim usb-camera` is asked to do.
#[derive(Debug, Clone)]
pub struct UsbCameraOptions {
    /// The recording directory whose `events.raw` is streamed.
    pub recording: PathBuf,
    /// Address to listen on (USB/IP's port is 3240).
    pub listen: SocketAddr,
    /// Bus id the host imports.
    pub busid: String,
    /// Link speed presented.
    pub speed: Speed,
    /// Stream pace.
    pub pace: Pace,
    /// The camera's serial number.
    pub serial: u64,
    /// Close the host's socket (an unplug) once, after this long of streaming.
    pub unplug_after: Option<Duration>,
    /// Stream faults.
    pub faults: StreamFaults,
    /// Every write to this register fails.
    pub fail_register: Option<u32>,
    /// Write the statistics (JSON) here every 100 ms.
    pub stats: Option<PathBuf>,
}

/// The statistics file's content.
#[derive(Debug, Clone, serde::Serialize)]
struct StatsFile<'a> {
    camera: &'a CameraStats,
    unplugs: u64,
    stream_bytes: usize,
    attached: bool,
}

/// Serves the emulated camera until the process is stopped.
pub fn serve(options: &UsbCameraOptions) -> anyhow::Result<()> {
    let stream = Arc::new(EventStream::open(&options.recording.join("events.raw"))?);
    let serial = format!("{:08X}", options.serial);
    let descriptors = DeviceDescriptors::build(&device::evk4_spec(options.speed, &serial))?;
    let identity = CameraIdentity {
        serial: options.serial,
        ..Default::default()
    };
    let camera = Evk4Device::new(
        descriptors,
        identity,
        stream.clone(),
        Playback::new(options.pace, options.faults),
        options.fail_register,
    );
    let listener = TcpListener::bind(options.listen)
        .map_err(|e| anyhow::anyhow!("cannot listen on {}: {e}", options.listen))?;
    let busid = BusId::new(&options.busid)
        .map_err(|e| anyhow::anyhow!("bus id `{}`: {e}", options.busid))?;
    let server = server::spawn(listener, camera, ServerConfig::new(busid))?;
    eprintln!(
        "usb-camera: EVK4 {serial} on {} (bus id {}), streaming {} ({} bytes, {:.2} s) {}",
        server.local_addr(),
        options.busid,
        options.recording.display(),
        stream.len(),
        stream.end_us() as f64 * 1e-6,
        match options.pace {
            Pace::Realtime => "in real time",
            Pace::Fast => "as fast as the host reads",
        }
    );
    let waker = server.waker();
    let mut unplugs = 0u64;
    let mut last_stats = Instant::now();
    loop {
        // The pump asks the device again on every wake: in real time this releases the next chunks.
        std::thread::sleep(Duration::from_millis(1));
        waker.wake();
        let since = server.with_device(|d| d.streaming_since);
        if let (Some(after), Some(since), 0) = (options.unplug_after, since, unplugs)
            && since.elapsed() >= after
            && server.disconnect()
        {
            unplugs += 1;
            eprintln!(
                "usb-camera: unplugged after {:.3} s of streaming (fault)",
                after.as_secs_f64()
            );
        }
        if let Some(path) = &options.stats
            && last_stats.elapsed() >= Duration::from_millis(100)
        {
            last_stats = Instant::now();
            let stats = server.with_device(|d| d.stats());
            let file = StatsFile {
                camera: &stats,
                unplugs,
                stream_bytes: stream.len(),
                attached: server.is_attached(),
            };
            let tmp = path.with_extension("tmp");
            std::fs::write(&tmp, serde_json::to_vec_pretty(&file)?)?;
            std::fs::rename(&tmp, path)?;
        }
    }
}

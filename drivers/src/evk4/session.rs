//! An EVK4 streaming: opened, brought up, its stale data flushed, its data endpoint running into a ring, and
//! the sensor started. The unit the live source and the recorder open, lose and reopen.

use super::camera::{Evk4, SensorSettings};
use super::error::CameraError;
use super::identity::DATA_IN;
use super::stream::{DataStream, StreamConfig};
use crate::transfer_ring::TransferRing;
use std::sync::Arc;
use std::time::Duration;

/// How long the flush before start waits for stale data.
const FLUSH_TIMEOUT: Duration = Duration::from_millis(100);

/// A camera whose data flows into a ring.
pub struct StreamingCamera {
    /// The camera (its identity: `serial`, `release`, `sensor`, `speed`).
    pub camera: Evk4,
    /// Its data stream.
    pub stream: DataStream,
}

impl StreamingCamera {
    /// Opens the camera with `serial` (or the first one) through a fresh context (a fresh context rescans the
    /// bus: a context's device list follows hotplug events, which need a running udevd), brings it up with
    /// `settings`, flushes it, starts `config`'s transfers into `ring` and starts the sensor.
    pub fn start(
        serial: Option<&str>,
        settings: &SensorSettings,
        config: StreamConfig,
        ring: &Arc<TransferRing>,
    ) -> Result<Self, CameraError> {
        let context = rusb::Context::new().map_err(CameraError::NoUsb)?;
        let camera = Evk4::open(&context, serial)?;
        camera.bring_up(settings)?;
        camera.flush_data(FLUSH_TIMEOUT)?;
        let stream = DataStream::start(camera.handle(), DATA_IN, config, ring.clone()).map_err(
            |source| CameraError::Usb {
                what: format!("data stream of EVK4 {}", camera.serial),
                source,
            },
        )?;
        camera.start()?;
        Ok(Self { camera, stream })
    }

    /// A line naming the camera: serial, firmware, sensor and link speed.
    pub fn describe(&self) -> String {
        format!(
            "EVK4 {} (firmware {}, {}, {})",
            self.camera.serial,
            super::identity::release_string(self.camera.release),
            self.camera.sensor,
            self.camera.speed
        )
    }
}

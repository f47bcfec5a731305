//! Discovery: every connected supported camera, with its identity read by opening it for a moment.

use super::camera::Evk4;
use super::error::{CameraError, speed_label};
use super::identity;
use rusb::UsbContext;

/// What discovery learnt of one connected camera.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CameraInfo {
    /// USB vendor id.
    pub vendor_id: u16,
    /// USB product id.
    pub product_id: u16,
    /// USB bus number.
    pub bus: u8,
    /// Device address on the bus.
    pub address: u8,
    /// Link speed label.
    pub speed: &'static str,
    /// Model ("EVK4", or what the camera said it is).
    pub model: String,
    /// Serial number (hex), when the camera could be opened.
    pub serial: Option<String>,
    /// Firmware release (`major.minor.patch`), when the camera could be opened.
    pub firmware: Option<String>,
    /// The sensor's compatible string (`psee,ccam5_imx636`), when the camera could be opened.
    pub sensor: Option<String>,
    /// Why this user cannot use it (None: it can be opened).
    pub problem: Option<String>,
}

/// Lists every connected supported camera, opening each (and closing it again) to read its identity.
pub fn list_cameras(context: &rusb::Context) -> Result<Vec<CameraInfo>, CameraError> {
    let devices = context.devices().map_err(CameraError::NoUsb)?;
    let mut out = Vec::new();
    for device in devices.iter() {
        let Ok(desc) = device.device_descriptor() else {
            continue;
        };
        if !identity::is_supported(desc.vendor_id(), desc.product_id()) {
            continue;
        }
        let mut info = CameraInfo {
            vendor_id: desc.vendor_id(),
            product_id: desc.product_id(),
            bus: device.bus_number(),
            address: device.address(),
            speed: speed_label(device.speed()),
            model: identity::PRODUCT.to_owned(),
            serial: None,
            firmware: None,
            sensor: None,
            problem: None,
        };
        match Evk4::from_device(&device) {
            Ok(camera) => {
                info.serial = Some(camera.serial.clone());
                info.firmware = Some(identity::release_string(camera.release));
                info.sensor = Some(camera.sensor.clone());
            }
            Err(e) => info.problem = Some(e.to_string()),
        }
        out.push(info);
    }
    Ok(out)
}

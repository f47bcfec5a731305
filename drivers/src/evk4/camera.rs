//! An EVK4 on the machine's USB stack (rusb on libusb, with an explicit context): discovery, opening by serial,
//! the Treuzell control channel, register access and the sensor's bring-up, start and stop.

use super::biases::BiasOffsets;
use super::error::{CameraError, register_name, speed_label, usb};
use super::identity::{self, CONTROL_IN, CONTROL_OUT, DATA_IN, INTERFACE};
use super::imx636::{self, RegisterOp, reg};
use super::treuzell::{MAX_ANSWER_BYTES, Request, property};
use rusb::UsbContext;
use std::time::Duration;

/// How long a control request or answer may take.
pub const CONTROL_TIMEOUT: Duration = Duration::from_secs(1);

/// An open EVK4 with its interface claimed.
pub struct Evk4 {
    handle: std::sync::Arc<rusb::DeviceHandle<rusb::Context>>,
    /// Serial number (hex).
    pub serial: String,
    /// Firmware release (`major << 16 | minor << 8 | patch`).
    pub release: u32,
    /// The sensor's compatible string.
    pub sensor: String,
    /// Link speed label.
    pub speed: &'static str,
}

impl Evk4 {
    /// Opens the camera with serial `serial`, or the first supported camera when `None`.
    pub fn open(context: &rusb::Context, serial: Option<&str>) -> Result<Self, CameraError> {
        let devices = context.devices().map_err(CameraError::NoUsb)?;
        let mut seen = Vec::new();
        let mut first_error = None;
        for device in devices.iter() {
            let Ok(desc) = device.device_descriptor() else {
                continue;
            };
            if !identity::is_supported(desc.vendor_id(), desc.product_id()) {
                continue;
            }
            match Self::from_device(&device) {
                Ok(camera) if serial.is_none_or(|s| s.eq_ignore_ascii_case(&camera.serial)) => {
                    return Ok(camera);
                }
                Ok(camera) => seen.push(camera.serial.clone()),
                Err(e) => {
                    seen.push(format!(
                        "bus {} address {}",
                        device.bus_number(),
                        device.address()
                    ));
                    first_error.get_or_insert(e);
                }
            }
        }
        if let (None, Some(e)) = (serial, first_error) {
            return Err(e);
        }
        Err(CameraError::NotFound {
            wanted: serial.map_or_else(String::new, |s| format!(" with serial {s}")),
            found: if seen.is_empty() {
                String::new()
            } else {
                format!(", connected: {}", seen.join(", "))
            },
        })
    }

    /// Opens `device`, claims its interface and reads its identity.
    pub(super) fn from_device(device: &rusb::Device<rusb::Context>) -> Result<Self, CameraError> {
        let handle = device.open().map_err(|e| match e {
            rusb::Error::Access => CameraError::Permission {
                bus: device.bus_number(),
                address: device.address(),
            },
            e => usb("open")(e),
        })?;
        handle
            .claim_interface(INTERFACE)
            .map_err(usb("claim of interface 0"))?;
        let mut model = [0u8; 2];
        let n = handle
            .read_control(
                0xC0,
                identity::MODEL_REQUEST,
                0,
                0,
                &mut model,
                CONTROL_TIMEOUT,
            )
            .map_err(usb("model request"))?;
        if n == 2 && model[0] == identity::MODEL_EVK3_HD {
            return Err(CameraError::Unsupported(
                "this camera is an EVK3 HD (same USB ids as the EVK4), which is not supported"
                    .into(),
            ));
        }
        let mut camera = Self {
            handle: std::sync::Arc::new(handle),
            serial: String::new(),
            release: 0,
            sensor: String::new(),
            speed: speed_label(device.speed()),
        };
        let serial = camera.request(&Request::read(property::SERIAL), "serial read")?;
        camera.serial = serial_string(&serial);
        let release = camera.request(&Request::read(property::RELEASE_VERSION), "release read")?;
        camera.release = super::treuzell::payload_word(&release, 0).unwrap_or(0);
        let compatible = camera.request(
            &Request::read_with(property::DEVICE_COMPATIBLE, &[0]),
            "sensor read",
        )?;
        camera.sensor = c_string(compatible.get(4..).unwrap_or_default());
        Ok(camera)
    }

    /// Sends `request` and returns its checked answer's payload.
    pub fn request(&self, request: &Request, what: &str) -> Result<Vec<u8>, CameraError> {
        let mut answer = [0u8; MAX_ANSWER_BYTES];
        let n = self.exchange(request, &mut answer, what)?;
        request
            .check_answer(&answer[..n])
            .map(<[u8]>::to_vec)
            .map_err(|source| CameraError::Protocol {
                what: what.to_owned(),
                source,
            })
    }

    fn exchange(
        &self,
        request: &Request,
        answer: &mut [u8],
        what: &str,
    ) -> Result<usize, CameraError> {
        let frame = request.encode();
        let written = self
            .handle
            .write_bulk(CONTROL_OUT, &frame, CONTROL_TIMEOUT)
            .map_err(usb(format!("{what} (request)")))?;
        if written != frame.len() {
            return Err(CameraError::Unsupported(format!(
                "{what}: short control write ({written} of {} bytes)",
                frame.len()
            )));
        }
        self.handle
            .read_bulk(CONTROL_IN, answer, CONTROL_TIMEOUT)
            .map_err(usb(format!("{what} (answer)")))
    }

    /// Reads the sensor register at `address`.
    pub fn read_register(&self, address: u32) -> Result<u32, CameraError> {
        let request = Request::register_read(address);
        let mut answer = [0u8; MAX_ANSWER_BYTES];
        let wrap = |source| CameraError::Register {
            address,
            name: register_name(address),
            action: String::new(),
            source: Box::new(source),
        };
        let n = self
            .exchange(&request, &mut answer, "register read")
            .map_err(wrap)?;
        request
            .check_register_answer(&answer[..n])
            .map_err(|source| {
                wrap(CameraError::Protocol {
                    what: "register read".into(),
                    source,
                })
            })
    }

    /// Writes `value` to the sensor register at `address`.
    pub fn write_register(&self, address: u32, value: u32) -> Result<(), CameraError> {
        self.request(&Request::register_write(address, value), "register write")
            .map(|_| ())
            .map_err(|source| CameraError::Register {
                address,
                name: register_name(address),
                action: format!(" = {value:#x}"),
                source: Box::new(source),
            })
    }

    /// Runs a register sequence, sleeping its delays.
    pub fn run(&self, ops: &[RegisterOp]) -> Result<(), CameraError> {
        for op in ops {
            match *op {
                RegisterOp::Write { address, value } => self.write_register(address, value)?,
                RegisterOp::Delay { us } => {
                    std::thread::sleep(Duration::from_micros(u64::from(us)))
                }
            }
        }
        Ok(())
    }

    /// Brings the sensor up: checks it is an IMX636 on a supported firmware, runs the initialisation sequence,
    /// sets the biases and the event-rate controller, and enables the trigger input (channel 0).
    pub fn bring_up(&self, settings: &SensorSettings) -> Result<(), CameraError> {
        if self.release < imx636::MIN_FIRMWARE_RELEASE {
            return Err(CameraError::Unsupported(format!(
                "EVK4 {} runs firmware {}; 3.8.0 or newer is needed (update it with Prophesee's tools)",
                self.serial,
                identity::release_string(self.release)
            )));
        }
        let chip = self.read_register(reg::CHIP_ID)?;
        if chip != imx636::IMX636_CHIP_ID {
            return Err(CameraError::Unsupported(format!(
                "EVK4 {}: register {:#06x} (chip_id) reads {chip:#010x}, not the IMX636's {:#010x}",
                self.serial,
                reg::CHIP_ID,
                imx636::IMX636_CHIP_ID
            )));
        }
        self.run(imx636::INIT)?;
        for (bias, offset) in settings.biases.iter() {
            let current = self.read_register(bias.address)?;
            self.write_register(
                bias.address,
                BiasOffsets::register_value(bias, offset, current),
            )?;
        }
        self.run(&imx636::erc(settings.erc_events_per_period))?;
        self.run(&[imx636::trigger_input(true)])
    }

    /// Starts the sensor's output.
    pub fn start(&self) -> Result<(), CameraError> {
        self.run(imx636::START)
    }

    /// Stops the sensor's output.
    pub fn stop(&self) -> Result<(), CameraError> {
        self.run(imx636::STOP)
    }

    /// Reads and discards what the data endpoint holds (stale data from an earlier session), until it returns
    /// nothing or `timeout` passes without data. Returns the bytes discarded.
    pub fn flush_data(&self, timeout: Duration) -> Result<u64, CameraError> {
        let mut buf = vec![0u8; 128 * 1024];
        let mut total = 0u64;
        loop {
            match self.handle.read_bulk(DATA_IN, &mut buf, timeout) {
                Ok(0) | Err(rusb::Error::Timeout) => return Ok(total),
                Ok(n) => total += n as u64,
                Err(e) => return Err(usb("data flush")(e)),
            }
        }
    }

    /// The open handle (shared with the data stream).
    pub fn handle(&self) -> std::sync::Arc<rusb::DeviceHandle<rusb::Context>> {
        self.handle.clone()
    }
}

/// The sensor settings a run applies at bring-up.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SensorSettings {
    /// Bias offsets from the factory codes.
    pub biases: BiasOffsets,
    /// The event-rate controller's cap in events per reference period, or `None` for no cap.
    pub erc_events_per_period: Option<u32>,
}

/// A serial answer (64-bit little-endian) as the hex string Prophesee's tools print.
pub fn serial_string(payload: &[u8]) -> String {
    let mut bytes = [0u8; 8];
    for (b, p) in bytes.iter_mut().zip(payload) {
        *b = *p;
    }
    let v = u64::from_le_bytes(bytes);
    if v >> 32 == 0 {
        format!("{v:08X}")
    } else {
        format!("{v:016X}")
    }
}

/// A NUL-terminated string from an answer.
fn c_string(bytes: &[u8]) -> String {
    let end = bytes.iter().position(|&b| b == 0).unwrap_or(bytes.len());
    String::from_utf8_lossy(&bytes[..end]).into_owned()
}

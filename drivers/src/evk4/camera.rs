//! An EVK4 on the machine's USB stack (rusb on libusb, with an explicit context): discovery, opening by serial,
//! the Treuzell control channel, register access and the sensor's bring-up, start and stop.

use super::biases::{BiasError, BiasOffsets};
use super::identity::{self, CONTROL_IN, CONTROL_OUT, DATA_IN, INTERFACE};
use super::imx636::{self, RegisterOp, reg};
use super::treuzell::{MAX_ANSWER_BYTES, Request, TreuzellError, property};
use rusb::UsbContext;
use std::time::Duration;
use thiserror::Error;

/// How long a control request or answer may take.
pub const CONTROL_TIMEOUT: Duration = Duration::from_secs(1);

/// Why a camera could not be found, opened or driven. Each names the camera or register concerned.
#[derive(Debug, Error)]
pub enum CameraError {
    /// The USB stack itself is unusable (no usbfs, no libusb).
    #[error("USB is not usable on this machine: {0}")]
    NoUsb(rusb::Error),
    /// No supported camera (with that serial) is connected.
    #[error("no EVK4{wanted} is connected{found}")]
    NotFound {
        /// " with serial X" or empty.
        wanted: String,
        /// The cameras that are connected, if any (", connected: ...").
        found: String,
    },
    /// This user may not open the device.
    #[error(
        "cannot open the EVK4 at bus {bus} address {address}: permission denied (install config/99-eventtrack6d.rules: sudo cp config/99-eventtrack6d.rules /etc/udev/rules.d/ && sudo udevadm control --reload && sudo udevadm trigger, then replug)"
    )]
    Permission {
        /// USB bus number.
        bus: u8,
        /// Device address on the bus.
        address: u8,
    },
    /// The camera went away (unplugged, or its link reset).
    #[error("the EVK4 was disconnected")]
    Disconnected,
    /// A USB operation failed.
    #[error("USB {what} failed: {source}")]
    Usb {
        /// What was being done.
        what: String,
        /// libusb's error.
        source: rusb::Error,
    },
    /// A control request's answer was refused.
    #[error("{what}: {source}")]
    Protocol {
        /// What was being done.
        what: String,
        /// Why the answer was refused.
        source: TreuzellError,
    },
    /// A register access failed.
    #[error("register {address:#06x} ({name}){action}: {source}")]
    Register {
        /// The register's address.
        address: u32,
        /// Its name, or "sensor register".
        name: &'static str,
        /// " = value" for a write, "" for a read.
        action: String,
        /// What failed.
        source: Box<CameraError>,
    },
    /// The device is not what this driver drives.
    #[error("{0}")]
    Unsupported(String),
    /// A bias setting the sensor does not allow.
    #[error(transparent)]
    Bias(#[from] BiasError),
}

impl CameraError {
    /// Whether reopening later may succeed: the camera is absent, gone, busy or not yet accessible, as opposed to a
    /// camera that refuses its configuration or is not supported (retrying cannot help).
    pub fn is_transient(&self) -> bool {
        match self {
            CameraError::NotFound { .. }
            | CameraError::Disconnected
            | CameraError::Permission { .. }
            | CameraError::Usb { .. } => true,
            CameraError::Register { source, .. } => source.is_disconnect(),
            _ => false,
        }
    }

    /// Whether the camera is gone (a reopen may bring it back), as opposed to a fault of the request.
    pub fn is_disconnect(&self) -> bool {
        match self {
            CameraError::Disconnected => true,
            CameraError::Usb { source, .. } => matches!(source, rusb::Error::NoDevice),
            CameraError::Register { source, .. } => source.is_disconnect(),
            _ => false,
        }
    }
}

fn usb(what: impl Into<String>) -> impl FnOnce(rusb::Error) -> CameraError {
    let what = what.into();
    move |source| match source {
        rusb::Error::NoDevice => CameraError::Disconnected,
        source => CameraError::Usb { what, source },
    }
}

/// The name of a register the driver writes by name, for error messages.
pub fn register_name(address: u32) -> &'static str {
    match address {
        reg::ROI_CTRL => "roi_ctrl",
        reg::CHIP_ID => "chip_id",
        reg::ANALOG_CTRL => "analog_ctrl",
        0x1000..=0x1050 => "bias",
        0x6000..=0x6FFF => "erc",
        reg::EDF_CONTROL => "edf_control (trigger input)",
        reg::READOUT_CTRL => "readout_ctrl",
        reg::TIME_BASE_CTRL => "time_base_ctrl",
        reg::RO_CTRL => "ro_ctrl",
        reg::MIPI_CTRL => "mipi_ctrl",
        _ => "sensor register",
    }
}

/// The USB link speed as a short label.
pub fn speed_label(speed: rusb::Speed) -> &'static str {
    match speed {
        rusb::Speed::Low => "low (1.5 Mb/s)",
        rusb::Speed::Full => "full (12 Mb/s)",
        rusb::Speed::High => "high (480 Mb/s)",
        rusb::Speed::Super => "super (5 Gb/s)",
        rusb::Speed::SuperPlus => "super+ (10 Gb/s)",
        _ => "unknown",
    }
}

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
    fn from_device(device: &rusb::Device<rusb::Context>) -> Result<Self, CameraError> {
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

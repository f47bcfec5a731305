//! Why an EVK4 could not be found, opened or driven, with the register and link names the messages use.

use super::biases::BiasError;
use super::imx636::reg;
use super::treuzell::TreuzellError;
use thiserror::Error;

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

pub(super) fn usb(what: impl Into<String>) -> impl FnOnce(rusb::Error) -> CameraError {
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

//! What an emulated device implements: the `UsbDevice` trait and the outcomes of its transfers.

use thiserror::Error;

use crate::descriptors::DeviceDescriptors;
use crate::protocol::SetupPacket;

/// Linux errno values a `RET_SUBMIT` status carries, negated.
pub mod errno {
    /// Broken pipe: the endpoint stalled (`-EPIPE` on the wire).
    pub const EPIPE: i32 = 32;
    /// Value too large: the device sent more than the host asked for.
    pub const EOVERFLOW: i32 = 75;
    /// Connection reset: the request was unlinked before it completed.
    pub const ECONNRESET: i32 = 104;
}

/// Why a transfer failed; the host sees it as the `RET_SUBMIT` status.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
pub enum UrbError {
    /// The endpoint stalls (status `-EPIPE`). A bulk endpoint stays halted until the host clears the halt.
    #[error("endpoint stalled")]
    Stall,
    /// Another failure, as a positive Linux errno (sent negated).
    #[error("transfer failed with errno {0}")]
    Errno(i32),
}

/// Answer of a device to a bulk-in request.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum BulkIn {
    /// Data for the request: at most the `max_len` asked for (longer data completes it with `-EOVERFLOW`).
    Data(Vec<u8>),
    /// No data yet: the request stays queued and is asked again after the device calls `Waker::wake`.
    Pending,
    /// The transfer fails.
    Failed(UrbError),
}

/// An emulated USB device, as the server sees it. Calls come from the server's threads one at a time (the
/// device sits behind a mutex) and must not block: a bulk-in request without data answers `Pending`, and
/// whoever later produces data calls the server's `Waker`.
pub trait UsbDevice: Send + 'static {
    /// The device's standard descriptors; read once when the server starts.
    fn descriptors(&self) -> &DeviceDescriptors;

    /// A request on endpoint 0 the server does not answer itself: class, vendor, and standard requests to an
    /// interface other than status, feature and alternate setting (e.g. a class descriptor). `data_out` is
    /// the data stage of an out request; an in request returns its data (cut to `wLength`).
    fn control(&mut self, setup: SetupPacket, data_out: &[u8]) -> Result<Vec<u8>, UrbError> {
        let _ = (setup, data_out);
        Err(UrbError::Stall)
    }

    /// Data the host sent to bulk-out endpoint `endpoint` (its address, e.g. 0x02).
    fn bulk_out(&mut self, endpoint: u8, data: &[u8]) -> Result<(), UrbError>;

    /// The oldest queued bulk-in request of `endpoint` (its address, e.g. 0x81) asks for up to `max_len`
    /// bytes.
    fn bulk_in(&mut self, endpoint: u8, max_len: usize) -> BulkIn;

    /// The host cleared the halt of `endpoint` (`CLEAR_FEATURE(ENDPOINT_HALT)`).
    fn clear_halt(&mut self, endpoint: u8) {
        let _ = endpoint;
    }

    /// The host selected configuration `value` (0: unconfigured) with `SET_CONFIGURATION`.
    fn configured(&mut self, value: u8) {
        let _ = value;
    }

    /// The host went away (socket closed or disconnected); queued requests were dropped.
    fn detached(&mut self) {}
}

impl UrbError {
    /// The `RET_SUBMIT` status: a negative errno.
    pub fn status(self) -> i32 {
        match self {
            Self::Stall => -errno::EPIPE,
            Self::Errno(code) => -code.saturating_abs(),
        }
    }
}

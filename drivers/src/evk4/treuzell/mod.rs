//! The Treuzell control protocol of Prophesee's USB cameras: typed requests and checked answers.
//!
//! A frame is `u32 property | u32 payload length | payload`, little-endian, written to the control OUT endpoint
//! and answered on the control IN endpoint. A write sets [`WRITE_FLAG`] on the property; the answer echoes the
//! request's property, with [`FAILURE_FLAG`] added when the command failed (its payload then ends with an errno),
//! or is the bare [`UNKNOWN_COMMAND`] when the device does not implement it. Pure encoding and decoding: the
//! transport is the caller's.

use thiserror::Error;

/// Added to a property to request a write.
pub const WRITE_FLAG: u32 = 0x4000_0000;
/// Added to the echoed property by a device whose command failed.
pub const FAILURE_FLAG: u32 = 0x8000_0000;
/// The whole answer property of a device that does not implement the command.
pub const UNKNOWN_COMMAND: u32 = FAILURE_FLAG;
/// Bytes of a frame header (property and payload length).
pub const HEADER_BYTES: usize = 8;
/// The largest answer a device sends (bytes, header included): the size of the read buffer.
pub const MAX_ANSWER_BYTES: usize = 1024;

/// Properties (command codes) used by the EVK4 driver.
pub mod property {
    /// FPGA state (read), or a reset with a magic value (write).
    pub const FPGA_STATE: u32 = 0x71;
    /// The camera's serial number (64-bit answer).
    pub const SERIAL: u32 = 0x72;
    /// The firmware release version (`major << 16 | minor << 8 | patch`).
    pub const RELEASE_VERSION: u32 = 0x79;
    /// The firmware build date (seconds since the Unix epoch).
    pub const BUILD_DATE: u32 = 0x7A;
    /// Number of devices behind the board.
    pub const DEVICE_COUNT: u32 = 0x10000;
    /// A device's name (payload: device index).
    pub const DEVICE_NAME: u32 = 0x10001;
    /// A device's compatible string, for example `psee,ccam5_imx636` (payload: device index).
    pub const DEVICE_COMPATIBLE: u32 = 0x10003;
    /// A device's 32-bit register (payload: device index, address, value or count).
    pub const DEVICE_REGISTER: u32 = 0x10102;
}

/// One control request, ready to be encoded.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Request {
    /// The property with [`WRITE_FLAG`] when it is a write.
    pub property: u32,
    /// The payload (little-endian words for every command the driver sends).
    pub payload: Vec<u8>,
}

/// Why an answer was refused. Each names the request's property so a log line says which command failed.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum TreuzellError {
    /// Fewer bytes than a header.
    #[error("answer to property {property:#x} is {len} bytes, shorter than the 8-byte header")]
    TooShort {
        /// The request's property.
        property: u32,
        /// Bytes received.
        len: usize,
    },
    /// The header's length field disagrees with the bytes received.
    #[error(
        "answer to property {property:#x} declares {declared} payload bytes but carries {actual}"
    )]
    LengthMismatch {
        /// The request's property.
        property: u32,
        /// The header's length field.
        declared: u32,
        /// Payload bytes actually received.
        actual: usize,
    },
    /// The device does not implement the command.
    #[error("the camera does not implement property {property:#x}")]
    UnknownCommand {
        /// The request's property.
        property: u32,
    },
    /// The device ran the command and it failed.
    #[error("the camera refused property {property:#x} (errno {errno})")]
    Failed {
        /// The request's property.
        property: u32,
        /// The device's error number (0 when the answer carries none).
        errno: u32,
    },
    /// The answer is for another property.
    #[error("answer to property {property:#x} carries property {answered:#x}")]
    PropertyMismatch {
        /// The request's property.
        property: u32,
        /// The answer's property.
        answered: u32,
    },
    /// A register read answer that does not repeat the request or carries no value.
    #[error("register {address:#06x}: malformed read answer ({reason})")]
    RegisterAnswer {
        /// The register's address.
        address: u32,
        /// What was wrong.
        reason: &'static str,
    },
}

fn words(values: &[u32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

impl Request {
    /// A read of `property` with no payload.
    pub fn read(property: u32) -> Self {
        Self {
            property,
            payload: Vec::new(),
        }
    }

    /// A read of `property` with little-endian word arguments.
    pub fn read_with(property: u32, args: &[u32]) -> Self {
        Self {
            property,
            payload: words(args),
        }
    }

    /// A write of `property` with little-endian word arguments.
    pub fn write(property: u32, args: &[u32]) -> Self {
        Self {
            property: property | WRITE_FLAG,
            payload: words(args),
        }
    }

    /// A read of the sensor's (device 0) 32-bit register at `address`.
    pub fn register_read(address: u32) -> Self {
        Self::read_with(property::DEVICE_REGISTER, &[0, address, 1])
    }

    /// A write of `value` to the sensor's (device 0) 32-bit register at `address`.
    pub fn register_write(address: u32, value: u32) -> Self {
        Self::write(property::DEVICE_REGISTER, &[0, address, value])
    }

    /// The frame's bytes.
    pub fn encode(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(HEADER_BYTES + self.payload.len());
        out.extend_from_slice(&self.property.to_le_bytes());
        // Payloads are built from a handful of words; a length over u32 cannot be built by this API.
        out.extend_from_slice(&(self.payload.len() as u32).to_le_bytes());
        out.extend_from_slice(&self.payload);
        out
    }

    /// Checks `answer` against this request and returns its payload.
    pub fn check_answer<'a>(&self, answer: &'a [u8]) -> Result<&'a [u8], TreuzellError> {
        let property = self.property;
        let (answered, declared, payload) = split_frame(answer).ok_or(TreuzellError::TooShort {
            property,
            len: answer.len(),
        })?;
        if declared as usize != payload.len() {
            return Err(TreuzellError::LengthMismatch {
                property,
                declared,
                actual: payload.len(),
            });
        }
        if answered == UNKNOWN_COMMAND {
            return Err(TreuzellError::UnknownCommand { property });
        }
        if answered == property | FAILURE_FLAG {
            let errno = payload
                .chunks_exact(4)
                .nth(1)
                .map_or(0, |w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]));
            return Err(TreuzellError::Failed { property, errno });
        }
        if answered != property {
            return Err(TreuzellError::PropertyMismatch { property, answered });
        }
        Ok(payload)
    }

    /// Checks the answer to a [`Request::register_read`] and returns the register's value: the answer must
    /// repeat the request's 20 bytes but the last 4, which hold the value.
    pub fn check_register_answer(&self, answer: &[u8]) -> Result<u32, TreuzellError> {
        let address = self
            .payload
            .get(4..8)
            .map_or(0, |w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]));
        let payload = self.check_answer(answer)?;
        if payload.len() != 12 {
            return Err(TreuzellError::RegisterAnswer {
                address,
                reason: "not 12 payload bytes",
            });
        }
        if payload[..8] != self.payload[..8] {
            return Err(TreuzellError::RegisterAnswer {
                address,
                reason: "device or address not repeated",
            });
        }
        Ok(u32::from_le_bytes([
            payload[8],
            payload[9],
            payload[10],
            payload[11],
        ]))
    }
}

/// Splits a frame into (property, declared payload length, payload bytes); `None` when shorter than a header.
pub fn split_frame(frame: &[u8]) -> Option<(u32, u32, &[u8])> {
    let header = frame.get(..HEADER_BYTES)?;
    let property = u32::from_le_bytes([header[0], header[1], header[2], header[3]]);
    let declared = u32::from_le_bytes([header[4], header[5], header[6], header[7]]);
    Some((property, declared, &frame[HEADER_BYTES..]))
}

/// An answer frame: `property`, then `payload` (the device's side of the protocol, used by emulators).
pub fn encode_answer(property: u32, payload: &[u8]) -> Vec<u8> {
    Request {
        property,
        payload: payload.to_vec(),
    }
    .encode()
}

/// A little-endian word of `payload` at word index `i`, if present.
pub fn payload_word(payload: &[u8], i: usize) -> Option<u32> {
    let w = payload.get(4 * i..4 * i + 4)?;
    Some(u32::from_le_bytes([w[0], w[1], w[2], w[3]]))
}

#[cfg(test)]
mod tests;

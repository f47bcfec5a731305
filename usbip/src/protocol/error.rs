//! What can be wrong with bytes that claim to be a USB/IP message.

use thiserror::Error;

/// Why bytes do not decode to a USB/IP message. Decoding never panics; every malformed input maps to one of
/// these.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum DecodeError {
    /// The input ends before the message does: `needed` bytes in all are required for `what`, `available`
    /// were given. A stream reader reads up to `needed` and decodes again.
    #[error("truncated {what}: {needed} bytes needed, {available} available")]
    Truncated {
        /// The message or field being read.
        what: &'static str,
        /// Bytes the message needs in all, from its first byte.
        needed: usize,
        /// Bytes given.
        available: usize,
    },
    /// An operation header carries a protocol version other than 0x0111.
    #[error("unsupported USB/IP version {0:#06x} (expected 0x0111)")]
    BadVersion(u16),
    /// An operation header carries a code that is not a known request or reply.
    #[error("unknown USB/IP operation code {0:#06x}")]
    UnknownOpCode(u16),
    /// A 48-byte URB header carries a command that is not CMD/RET_SUBMIT or CMD/RET_UNLINK.
    #[error("unknown USB/IP command {0:#010x}")]
    UnknownCommand(u32),
    /// A direction field other than 0 (out) or 1 (in).
    #[error("bad direction {0} (expected 0 or 1)")]
    BadDirection(u32),
    /// A length field is over its cap (`MAX_TRANSFER_LENGTH`, `MAX_ISO_PACKETS`).
    #[error("{what} {value} exceeds the maximum {max}")]
    TooLarge {
        /// The field.
        what: &'static str,
        /// Its value.
        value: u32,
        /// The documented cap.
        max: u32,
    },
    /// A fixed-size string field (bus id, sysfs path) has no NUL terminator or is not UTF-8.
    #[error("bad {0} string field: no NUL terminator or not UTF-8")]
    BadString(&'static str),
}

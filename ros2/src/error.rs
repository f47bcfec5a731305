//! Why bytes are not a valid message or attachment.

use crate::ATTACHMENT_LEN;

/// Why bytes are not a valid CDR message or rmw_zenoh attachment. Every variant names the field.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum CdrError {
    /// The input ended before a field was complete.
    #[error("truncated: {field} needs {needed} bytes at offset {offset}, but the input has {len}")]
    Truncated {
        /// Field being read.
        field: &'static str,
        /// Byte offset (from the start of the input, header included) where the field starts.
        offset: usize,
        /// Bytes the field needs.
        needed: usize,
        /// Total input length.
        len: usize,
    },
    /// The encapsulation header is not little-endian plain CDR.
    #[error(
        "unsupported CDR encapsulation {0:02x?} (expected 00 01 00 00, little-endian plain CDR)"
    )]
    Encapsulation([u8; 4]),
    /// A string length of 0 (CDR strings count their terminating NUL, so the minimum is 1).
    #[error("{0}: string length is 0 (CDR string lengths include the terminating NUL)")]
    ZeroLengthString(&'static str),
    /// A string's last byte is not NUL.
    #[error("{0}: string is not NUL-terminated")]
    MissingNul(&'static str),
    /// A string contains bytes that are not UTF-8.
    #[error("{0}: string is not valid UTF-8")]
    NotUtf8(&'static str),
    /// A `bool` byte other than 0 or 1.
    #[error("{field}: bool byte is {value:#04x} (only 0 and 1 are booleans)")]
    NotBool {
        /// Field being read.
        field: &'static str,
        /// The byte.
        value: u8,
    },
    /// A sequence longer than the bytes left could hold, or longer than the field allows.
    #[error("{field}: sequence of {count} elements does not fit ({reason})")]
    SequenceLength {
        /// Field being read.
        field: &'static str,
        /// The length the input gives.
        count: u64,
        /// Why it is refused.
        reason: &'static str,
    },
    /// A timestamp that does not fit ROS 2's `builtin_interfaces/Time` (`int32` seconds).
    #[error("time {nanos} ns is outside the range of builtin_interfaces/Time (int32 seconds)")]
    TimeOutOfRange {
        /// The time, nanoseconds.
        nanos: i128,
    },
    /// An attachment of the wrong size.
    #[error("attachment: {len} bytes, expected {ATTACHMENT_LEN}")]
    AttachmentLength {
        /// Length received.
        len: usize,
    },
    /// An attachment whose GID length prefix is not 16.
    #[error("attachment: GID length prefix is {0:#04x}, expected 0x10 (16 bytes)")]
    AttachmentGidLength(u8),
}

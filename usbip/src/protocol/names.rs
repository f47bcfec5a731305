//! Fixed-size, NUL-terminated string fields: the bus id and the sysfs path of a device record.

use std::fmt;

use thiserror::Error;

use super::error::DecodeError;

/// A string stored in an `N`-byte field, NUL-padded: at most `N - 1` UTF-8 bytes and no NUL inside.
#[derive(Debug, Clone, PartialEq, Eq, Hash, Default)]
pub struct FixedName<const N: usize>(String);

/// A bus id such as `"1-1"` (32-byte field).
pub type BusId = FixedName<32>;

/// A sysfs device path (256-byte field), informational only.
pub type SysfsPath = FixedName<256>;

/// Why a string cannot be stored in a fixed-size field.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum NameError {
    /// Longer than the field allows (`max` bytes, leaving room for the NUL terminator).
    #[error("{len} bytes do not fit a field of {max} bytes plus NUL")]
    TooLong {
        /// Length of the string in bytes.
        len: usize,
        /// Longest string the field holds, in bytes.
        max: usize,
    },
    /// Contains a NUL byte, which would end the field early.
    #[error("string contains a NUL byte")]
    ContainsNul,
}

impl<const N: usize> FixedName<N> {
    /// The name, if it fits: at most `N - 1` bytes, no NUL.
    pub fn new(name: &str) -> Result<Self, NameError> {
        if name.len() >= N {
            return Err(NameError::TooLong {
                len: name.len(),
                max: N.saturating_sub(1),
            });
        }
        if name.contains('\0') {
            return Err(NameError::ContainsNul);
        }
        Ok(Self(name.to_owned()))
    }

    /// The name as text.
    pub fn as_str(&self) -> &str {
        &self.0
    }

    /// The `N`-byte field: the name followed by NUL padding.
    pub fn to_field(&self) -> [u8; N] {
        let mut field = [0; N];
        field[..self.0.len()].copy_from_slice(self.0.as_bytes());
        field
    }

    /// Reads the name from an `N`-byte field up to its first NUL; `what` names the field in errors.
    pub fn from_field(field: &[u8; N], what: &'static str) -> Result<Self, DecodeError> {
        let end = field
            .iter()
            .position(|&b| b == 0)
            .ok_or(DecodeError::BadString(what))?;
        let text = std::str::from_utf8(&field[..end]).map_err(|_| DecodeError::BadString(what))?;
        Ok(Self(text.to_owned()))
    }
}

impl<const N: usize> fmt::Display for FixedName<N> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

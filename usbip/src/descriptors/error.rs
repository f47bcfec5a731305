//! Why a `DeviceSpec` cannot be turned into descriptors.

use thiserror::Error;

/// A `DeviceSpec` that breaks a descriptor limit.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum DescriptorError {
    /// A string longer than 126 UTF-16 code units (a descriptor is at most 255 bytes).
    #[error("string {0:?} is longer than 126 UTF-16 code units")]
    StringTooLong(String),
    /// More than 255 strings.
    #[error("more than 255 strings")]
    TooManyStrings,
    /// More than 255 interfaces, or more than 30 endpoints in one interface.
    #[error("too many interfaces or endpoints")]
    TooMany,
    /// An endpoint address that is not a bulk endpoint 1-15 (bit 7 the direction), or repeats one.
    #[error("bad or repeated endpoint address {0:#04x}")]
    BadEndpoint(u8),
    /// A SuperSpeed `bMaxBurst` over 15.
    #[error("max burst {0} exceeds 15")]
    BadMaxBurst(u8),
    /// The configuration descriptor set exceeds 65535 bytes.
    #[error("configuration descriptors exceed 65535 bytes")]
    ConfigurationTooLong,
}

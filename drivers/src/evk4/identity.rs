//! How an EVK4 identifies itself on USB: vendor and product ids, interface, endpoints and strings.

/// `(vendor id, product id)` of every supported camera (Prophesee/Cypress and the OEM variants).
pub const SUPPORTED_IDS: [(u16, u16); 5] = [
    (0x04B4, 0x00F4),
    (0x04B4, 0x00F5),
    (0x31F7, 0x0003),
    (0x31F7, 0x0004),
    (0x1409, 0x8E00),
];

/// The vendor interface that carries control and data.
pub const INTERFACE: u8 = 0;
/// Control requests go out on this bulk endpoint.
pub const CONTROL_OUT: u8 = 0x02;
/// Control answers come back on this bulk endpoint.
pub const CONTROL_IN: u8 = 0x82;
/// EVT 3.0 data comes in on this bulk endpoint.
pub const DATA_IN: u8 = 0x81;
/// A vendor request on EP0 (bmRequestType `0xC0`, this bRequest, 2 bytes) whose first byte tells EVK4 from EVK3 HD.
pub const MODEL_REQUEST: u8 = 0x72;
/// The first byte of [`MODEL_REQUEST`]'s answer on an EVK4.
pub const MODEL_EVK4: u8 = 0x31;
/// The first byte of [`MODEL_REQUEST`]'s answer on an EVK3 HD (same ids, not supported).
pub const MODEL_EVK3_HD: u8 = 0x30;
/// The product string of an EVK4.
pub const PRODUCT: &str = "EVK4";

/// Whether `(vendor, product)` is a supported camera's.
pub fn is_supported(vendor: u16, product: u16) -> bool {
    SUPPORTED_IDS.contains(&(vendor, product))
}

/// A firmware release number (`major << 16 | minor << 8 | patch`) as `major.minor.patch`.
pub fn release_string(release: u32) -> String {
    format!(
        "{}.{}.{}",
        release >> 16,
        (release >> 8) & 0xFF,
        release & 0xFF
    )
}

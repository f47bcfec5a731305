//! Byte layouts of the standard descriptors (USB 2.0 chapter 9, USB 3.2 chapter 9; little-endian).

use super::error::DescriptorError;
use super::spec::{DeviceSpec, EndpointSpec, InterfaceSpec, Speed};

/// `bDescriptorType` of a device descriptor.
pub const DEVICE: u8 = 1;
/// `bDescriptorType` of a configuration descriptor.
pub const CONFIGURATION: u8 = 2;
/// `bDescriptorType` of a string descriptor.
pub const STRING: u8 = 3;
/// `bDescriptorType` of an interface descriptor.
pub const INTERFACE: u8 = 4;
/// `bDescriptorType` of an endpoint descriptor.
pub const ENDPOINT: u8 = 5;
/// `bDescriptorType` of a device qualifier descriptor.
pub const DEVICE_QUALIFIER: u8 = 6;
/// `bDescriptorType` of a BOS descriptor.
pub const BOS: u8 = 0x0f;
/// `bDescriptorType` of a device capability descriptor (inside the BOS).
pub const DEVICE_CAPABILITY: u8 = 0x10;
/// `bDescriptorType` of a SuperSpeed endpoint companion descriptor.
pub const SS_ENDPOINT_COMPANION: u8 = 0x30;
/// LANGID of US English, the only language the string table offers.
pub const LANGID_EN_US: u16 = 0x0409;

/// The value `SET_CONFIGURATION` selects the one configuration with.
pub const CONFIGURATION_VALUE: u8 = 1;

const MAX_STRING_UNITS: usize = 126;
const BULK: u8 = 0x02;

/// String descriptor 0: the LANGID table.
pub fn langid_table() -> Vec<u8> {
    let [lo, hi] = LANGID_EN_US.to_le_bytes();
    vec![4, STRING, lo, hi]
}

/// A string descriptor: the text in UTF-16LE.
pub fn string_descriptor(text: &str) -> Result<Vec<u8>, DescriptorError> {
    let units: Vec<u16> = text.encode_utf16().collect();
    if units.len() > MAX_STRING_UNITS {
        return Err(DescriptorError::StringTooLong(text.to_owned()));
    }
    let mut out = vec![(2 + 2 * units.len()) as u8, STRING];
    out.extend(units.iter().flat_map(|unit| unit.to_le_bytes()));
    Ok(out)
}

fn bcd_usb(speed: Speed) -> u16 {
    match speed {
        Speed::High => 0x0200,
        Speed::Super => 0x0320,
    }
}

/// `bMaxPacketSize0`: 64 bytes at high speed, the exponent 9 (512 bytes) at SuperSpeed.
fn ep0_max_packet(speed: Speed) -> u8 {
    match speed {
        Speed::High => 64,
        Speed::Super => 9,
    }
}

/// String indices of the device descriptor: manufacturer, product, serial number (0: none).
#[derive(Debug, Clone, Copy, Default)]
pub struct DeviceStrings {
    /// `iManufacturer`.
    pub manufacturer: u8,
    /// `iProduct`.
    pub product: u8,
    /// `iSerialNumber`.
    pub serial_number: u8,
}

/// The 18-byte device descriptor.
pub fn device_descriptor(spec: &DeviceSpec, strings: DeviceStrings) -> [u8; 18] {
    let [usb_lo, usb_hi] = bcd_usb(spec.speed).to_le_bytes();
    let [vid_lo, vid_hi] = spec.vendor_id.to_le_bytes();
    let [pid_lo, pid_hi] = spec.product_id.to_le_bytes();
    let [dev_lo, dev_hi] = spec.bcd_device.to_le_bytes();
    [
        18,
        DEVICE,
        usb_lo,
        usb_hi,
        spec.device_class,
        spec.device_subclass,
        spec.device_protocol,
        ep0_max_packet(spec.speed),
        vid_lo,
        vid_hi,
        pid_lo,
        pid_hi,
        dev_lo,
        dev_hi,
        strings.manufacturer,
        strings.product,
        strings.serial_number,
        1,
    ]
}

/// The 10-byte device qualifier of a high-speed device (its other speed, full speed, has the same shape).
pub fn device_qualifier(spec: &DeviceSpec) -> [u8; 10] {
    let [usb_lo, usb_hi] = bcd_usb(Speed::High).to_le_bytes();
    let (class, subclass, protocol) = (
        spec.device_class,
        spec.device_subclass,
        spec.device_protocol,
    );
    [
        10,
        DEVICE_QUALIFIER,
        usb_lo,
        usb_hi,
        class,
        subclass,
        protocol,
        64,
        1,
        0,
    ]
}

fn endpoint(out: &mut Vec<u8>, speed: Speed, spec: EndpointSpec) -> Result<(), DescriptorError> {
    let [mps_lo, mps_hi] = speed.bulk_max_packet().to_le_bytes();
    out.extend_from_slice(&[7, ENDPOINT, spec.address, BULK, mps_lo, mps_hi, 0]);
    if speed == Speed::Super {
        if spec.max_burst > 15 {
            return Err(DescriptorError::BadMaxBurst(spec.max_burst));
        }
        out.extend_from_slice(&[6, SS_ENDPOINT_COMPANION, spec.max_burst, 0, 0, 0]);
    }
    Ok(())
}

fn interface(
    out: &mut Vec<u8>,
    speed: Speed,
    number: u8,
    spec: &InterfaceSpec,
    name_index: u8,
) -> Result<(), DescriptorError> {
    let endpoints = u8::try_from(spec.endpoints.len()).map_err(|_| DescriptorError::TooMany)?;
    if endpoints > 30 {
        return Err(DescriptorError::TooMany);
    }
    out.extend_from_slice(&[
        9,
        INTERFACE,
        number,
        0,
        endpoints,
        spec.class,
        spec.subclass,
        spec.protocol,
        name_index,
    ]);
    for &ep in &spec.endpoints {
        endpoint(out, speed, ep)?;
    }
    Ok(())
}

/// The configuration descriptor followed by its interfaces and endpoints; `interface_names[i]` is
/// interface `i`'s string index (0: none).
pub fn configuration(
    spec: &DeviceSpec,
    interface_names: &[u8],
) -> Result<Vec<u8>, DescriptorError> {
    let count = u8::try_from(spec.interfaces.len()).map_err(|_| DescriptorError::TooMany)?;
    let attributes = 0x80 | if spec.self_powered { 0x40 } else { 0 };
    let power_unit = match spec.speed {
        Speed::High => 2,
        Speed::Super => 8,
    };
    let max_power = u8::try_from(spec.max_power_ma / power_unit).unwrap_or(u8::MAX);
    let mut out = vec![
        9,
        CONFIGURATION,
        0,
        0,
        count,
        CONFIGURATION_VALUE,
        0,
        attributes,
        max_power,
    ];
    for (number, iface) in (0..count).zip(&spec.interfaces) {
        let name = interface_names
            .get(usize::from(number))
            .copied()
            .unwrap_or(0);
        interface(&mut out, spec.speed, number, iface, name)?;
    }
    let total = u16::try_from(out.len()).map_err(|_| DescriptorError::ConfigurationTooLong)?;
    out[2..4].copy_from_slice(&total.to_le_bytes());
    Ok(out)
}

/// The BOS of a SuperSpeed device: the USB 2.0 extension and the SuperSpeed USB device capability
/// (speeds full, high and super; full speed the lowest that works; U1 exit 10 µs, U2 exit 32 µs).
pub fn superspeed_bos() -> Vec<u8> {
    let usb2_extension = [7, DEVICE_CAPABILITY, 0x02, 0, 0, 0, 0];
    let superspeed = [
        10,
        DEVICE_CAPABILITY,
        0x03,
        0,
        0x0e,
        0x00,
        0x01,
        0x0a,
        0x20,
        0x00,
    ];
    let total = (5 + usb2_extension.len() + superspeed.len()) as u16;
    let [lo, hi] = total.to_le_bytes();
    let mut out = vec![5, BOS, lo, hi, 2];
    out.extend_from_slice(&usb2_extension);
    out.extend_from_slice(&superspeed);
    out
}

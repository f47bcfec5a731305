//! Operation messages, exchanged before a device is imported: the device list and the import.

use std::num::NonZeroU32;

use super::error::DecodeError;
use super::names::{BusId, FixedName, SysfsPath};
use super::wire::Reader;

/// The protocol version every operation header carries.
pub const USBIP_VERSION: u16 = 0x0111;
/// Operation code: the host asks for the exported devices.
pub const OP_REQ_DEVLIST: u16 = 0x8005;
/// Operation code: the list of exported devices.
pub const OP_REP_DEVLIST: u16 = 0x0005;
/// Operation code: the host asks to import the device with a bus id.
pub const OP_REQ_IMPORT: u16 = 0x8003;
/// Operation code: the answer to an import; on success the device record follows.
pub const OP_REP_IMPORT: u16 = 0x0003;
/// Bytes of an operation header: version, code, status.
pub const OP_HEADER_LEN: usize = 8;
/// Bytes of a device record (`struct usbip_usb_device`).
pub const DEVICE_RECORD_LEN: usize = 0x138;
/// Bytes of one interface entry of a device list: class, subclass, protocol, padding.
pub const INTERFACE_ENTRY_LEN: usize = 4;

/// A device as the protocol describes it (`struct usbip_usb_device`, 0x138 bytes).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DeviceRecord {
    /// Sysfs path of the device on the exporting side; informational.
    pub path: SysfsPath,
    /// Bus id the host imports the device by, e.g. `"1-1"`.
    pub busid: BusId,
    /// Bus number; with `devnum` it forms the devid `busnum << 16 | devnum`.
    pub busnum: u32,
    /// Device number on the bus.
    pub devnum: u32,
    /// Linux `enum usb_device_speed`: 2 full, 3 high, 5 super.
    pub speed: u32,
    /// `idVendor`.
    pub vendor_id: u16,
    /// `idProduct`.
    pub product_id: u16,
    /// `bcdDevice`, the device release number in BCD.
    pub bcd_device: u16,
    /// `bDeviceClass`.
    pub device_class: u8,
    /// `bDeviceSubClass`.
    pub device_subclass: u8,
    /// `bDeviceProtocol`.
    pub device_protocol: u8,
    /// `bConfigurationValue` of the active configuration (0: unconfigured).
    pub configuration_value: u8,
    /// `bNumConfigurations`.
    pub num_configurations: u8,
    /// `bNumInterfaces` of the active configuration.
    pub num_interfaces: u8,
}

/// Class triple of one interface, as listed after a device record in a device list.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct InterfaceClass {
    /// `bInterfaceClass`.
    pub class: u8,
    /// `bInterfaceSubClass`.
    pub subclass: u8,
    /// `bInterfaceProtocol`.
    pub protocol: u8,
}

/// One entry of a device list. Encoding writes `interfaces.len()` as the record's `bNumInterfaces`, so the
/// entry stays self-consistent; decoding reads as many interfaces as the record says.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ExportedDevice {
    /// The device.
    pub record: DeviceRecord,
    /// Its interfaces' class triples, in interface order (at most 255).
    pub interfaces: Vec<InterfaceClass>,
}

/// A request the host sends on a fresh connection.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum OpRequest {
    /// `OP_REQ_DEVLIST`: list the exported devices (the server then closes the connection).
    DevList,
    /// `OP_REQ_IMPORT`: attach the device with this bus id; URB traffic follows on the same connection.
    Import(BusId),
}

/// The operation a reply answers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OpKind {
    /// Device list.
    DevList,
    /// Import.
    Import,
}

/// A server's reply to an `OpRequest`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum OpReply {
    /// `OP_REP_DEVLIST` with status 0: the exported devices.
    DevList(Vec<ExportedDevice>),
    /// `OP_REP_IMPORT` with status 0 and the imported device's record.
    Imported(DeviceRecord),
    /// A reply with a non-zero status (1: refused, e.g. an unknown bus id); only the header is sent.
    Refused {
        /// Which request was refused.
        kind: OpKind,
        /// The status field.
        status: NonZeroU32,
    },
}

fn put_header(out: &mut Vec<u8>, code: u16, status: u32) {
    out.extend_from_slice(&USBIP_VERSION.to_be_bytes());
    out.extend_from_slice(&code.to_be_bytes());
    out.extend_from_slice(&status.to_be_bytes());
}

/// Reads an operation header: the code and status, after checking the version.
fn read_header(reader: &mut Reader<'_>) -> Result<(u16, u32), DecodeError> {
    let version = reader.u16()?;
    if version != USBIP_VERSION {
        return Err(DecodeError::BadVersion(version));
    }
    let code = reader.u16()?;
    let status = reader.u32()?;
    Ok((code, status))
}

impl DeviceRecord {
    /// The devid URB headers address this device by: `busnum << 16 | devnum`.
    pub fn devid(&self) -> u32 {
        (self.busnum << 16) | (self.devnum & 0xffff)
    }

    /// Appends the 0x138-byte record.
    pub fn encode_into(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.path.to_field());
        out.extend_from_slice(&self.busid.to_field());
        for word in [self.busnum, self.devnum, self.speed] {
            out.extend_from_slice(&word.to_be_bytes());
        }
        for half in [self.vendor_id, self.product_id, self.bcd_device] {
            out.extend_from_slice(&half.to_be_bytes());
        }
        out.extend_from_slice(&[
            self.device_class,
            self.device_subclass,
            self.device_protocol,
            self.configuration_value,
            self.num_configurations,
            self.num_interfaces,
        ]);
    }

    fn read(reader: &mut Reader<'_>) -> Result<Self, DecodeError> {
        reader.require(DEVICE_RECORD_LEN)?;
        Ok(Self {
            path: FixedName::from_field(&reader.array()?, "path")?,
            busid: FixedName::from_field(&reader.array()?, "busid")?,
            busnum: reader.u32()?,
            devnum: reader.u32()?,
            speed: reader.u32()?,
            vendor_id: reader.u16()?,
            product_id: reader.u16()?,
            bcd_device: reader.u16()?,
            device_class: reader.u8()?,
            device_subclass: reader.u8()?,
            device_protocol: reader.u8()?,
            configuration_value: reader.u8()?,
            num_configurations: reader.u8()?,
            num_interfaces: reader.u8()?,
        })
    }
}

impl OpRequest {
    /// The request's bytes: header, and for an import the 32-byte bus id.
    pub fn encode(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(OP_HEADER_LEN + 32);
        match self {
            Self::DevList => put_header(&mut out, OP_REQ_DEVLIST, 0),
            Self::Import(busid) => {
                put_header(&mut out, OP_REQ_IMPORT, 0);
                out.extend_from_slice(&busid.to_field());
            }
        }
        out
    }

    /// Decodes a request from the front of `bytes`; returns it and the bytes it used.
    pub fn decode(bytes: &[u8]) -> Result<(Self, usize), DecodeError> {
        let mut reader = Reader::new(bytes, "operation request");
        let (code, _status) = read_header(&mut reader)?;
        let request = match code {
            OP_REQ_DEVLIST => Self::DevList,
            OP_REQ_IMPORT => Self::Import(FixedName::from_field(&reader.array()?, "busid")?),
            other => return Err(DecodeError::UnknownOpCode(other)),
        };
        Ok((request, reader.position()))
    }
}

impl OpReply {
    /// The reply's bytes: header, then the device list or the imported record.
    pub fn encode(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(OP_HEADER_LEN + DEVICE_RECORD_LEN);
        match self {
            Self::DevList(devices) => {
                put_header(&mut out, OP_REP_DEVLIST, 0);
                out.extend_from_slice(&(devices.len() as u32).to_be_bytes());
                for device in devices {
                    let mut record = device.record.clone();
                    record.num_interfaces = device.interfaces.len().min(255) as u8;
                    record.encode_into(&mut out);
                    for interface in device.interfaces.iter().take(255) {
                        out.extend_from_slice(&[
                            interface.class,
                            interface.subclass,
                            interface.protocol,
                            0,
                        ]);
                    }
                }
            }
            Self::Imported(record) => {
                put_header(&mut out, OP_REP_IMPORT, 0);
                record.encode_into(&mut out);
            }
            Self::Refused { kind, status } => {
                let code = match kind {
                    OpKind::DevList => OP_REP_DEVLIST,
                    OpKind::Import => OP_REP_IMPORT,
                };
                put_header(&mut out, code, status.get());
            }
        }
        out
    }

    /// Decodes a reply from the front of `bytes`; returns it and the bytes it used.
    pub fn decode(bytes: &[u8]) -> Result<(Self, usize), DecodeError> {
        let mut reader = Reader::new(bytes, "operation reply");
        let (code, status) = read_header(&mut reader)?;
        let kind = match code {
            OP_REP_DEVLIST => OpKind::DevList,
            OP_REP_IMPORT => OpKind::Import,
            other => return Err(DecodeError::UnknownOpCode(other)),
        };
        if let Some(status) = NonZeroU32::new(status) {
            return Ok((Self::Refused { kind, status }, reader.position()));
        }
        let reply = match kind {
            OpKind::DevList => Self::DevList(read_devices(&mut reader)?),
            OpKind::Import => Self::Imported(DeviceRecord::read(&mut reader)?),
        };
        Ok((reply, reader.position()))
    }
}

/// Reads a device count and that many entries; the count only bounds the loop, so a huge count in short
/// input ends in `Truncated` without allocating for it.
fn read_devices(reader: &mut Reader<'_>) -> Result<Vec<ExportedDevice>, DecodeError> {
    let count = reader.u32()?;
    let mut devices = Vec::new();
    for _ in 0..count {
        let record = DeviceRecord::read(reader)?;
        reader.require(usize::from(record.num_interfaces) * INTERFACE_ENTRY_LEN)?;
        let mut interfaces = Vec::with_capacity(usize::from(record.num_interfaces));
        for _ in 0..record.num_interfaces {
            let [class, subclass, protocol, _padding] = reader.array()?;
            interfaces.push(InterfaceClass {
                class,
                subclass,
                protocol,
            });
        }
        devices.push(ExportedDevice { record, interfaces });
    }
    Ok(devices)
}

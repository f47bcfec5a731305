//! A device's standard descriptors, built from a `DeviceSpec`: device, one configuration with interfaces
//! and bulk endpoints, strings (UTF-16LE, LANGID table at index 0) and, at SuperSpeed, the BOS.

mod encode;
mod error;
mod spec;

pub use encode::{
    BOS, CONFIGURATION, CONFIGURATION_VALUE, DEVICE, DEVICE_CAPABILITY, DEVICE_QUALIFIER, ENDPOINT,
    INTERFACE, LANGID_EN_US, SS_ENDPOINT_COMPANION, STRING,
};
pub use error::DescriptorError;
pub use spec::{DeviceSpec, EndpointSpec, InterfaceSpec, Speed};

use crate::protocol::{BusId, DeviceRecord, InterfaceClass, SysfsPath};
use encode::DeviceStrings;

/// The descriptor bytes a device answers `GET_DESCRIPTOR` with, and the facts the device record needs.
/// Invariants: endpoint addresses are distinct bulk endpoints 1-15; every string index the descriptors
/// name exists.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DeviceDescriptors {
    spec: DeviceSpec,
    device: [u8; 18],
    configuration: Vec<u8>,
    strings: Vec<Vec<u8>>,
    bos: Option<Vec<u8>>,
    qualifier: Option<[u8; 10]>,
    endpoints: Vec<u8>,
}

/// Appends a string descriptor and returns its index, or 0 for no string.
fn add_string(strings: &mut Vec<Vec<u8>>, text: Option<&str>) -> Result<u8, DescriptorError> {
    let Some(text) = text else { return Ok(0) };
    let index = u8::try_from(strings.len()).map_err(|_| DescriptorError::TooManyStrings)?;
    strings.push(encode::string_descriptor(text)?);
    Ok(index)
}

fn endpoint_addresses(spec: &DeviceSpec) -> Result<Vec<u8>, DescriptorError> {
    let mut addresses: Vec<u8> = Vec::new();
    for address in spec
        .interfaces
        .iter()
        .flat_map(|i| i.endpoints.iter().map(|e| e.address))
    {
        let number = address & 0x7f;
        if !(1..=15).contains(&number) || addresses.contains(&address) {
            return Err(DescriptorError::BadEndpoint(address));
        }
        addresses.push(address);
    }
    Ok(addresses)
}

impl DeviceDescriptors {
    /// Builds every descriptor of `spec`, or says which limit it breaks.
    pub fn build(spec: &DeviceSpec) -> Result<Self, DescriptorError> {
        let endpoints = endpoint_addresses(spec)?;
        let mut strings = vec![encode::langid_table()];
        let device_strings = DeviceStrings {
            manufacturer: add_string(&mut strings, spec.manufacturer.as_deref())?,
            product: add_string(&mut strings, spec.product.as_deref())?,
            serial_number: add_string(&mut strings, spec.serial_number.as_deref())?,
        };
        let interface_names = spec
            .interfaces
            .iter()
            .map(|i| add_string(&mut strings, i.name.as_deref()))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self {
            device: encode::device_descriptor(spec, device_strings),
            configuration: encode::configuration(spec, &interface_names)?,
            bos: (spec.speed == Speed::Super).then(encode::superspeed_bos),
            qualifier: (spec.speed == Speed::High).then(|| encode::device_qualifier(spec)),
            strings,
            endpoints,
            spec: spec.clone(),
        })
    }

    /// The spec the descriptors were built from.
    pub fn spec(&self) -> &DeviceSpec {
        &self.spec
    }

    /// Bus speed.
    pub fn speed(&self) -> Speed {
        self.spec.speed
    }

    /// The 18-byte device descriptor.
    pub fn device(&self) -> &[u8] {
        &self.device
    }

    /// The configuration descriptor with its interfaces and endpoints (`wTotalLength` bytes).
    pub fn configuration(&self) -> &[u8] {
        &self.configuration
    }

    /// String descriptor `index` (0: the LANGID table), if it exists.
    pub fn string(&self, index: u8) -> Option<&[u8]> {
        self.strings.get(usize::from(index)).map(Vec::as_slice)
    }

    /// The BOS descriptor set (SuperSpeed only).
    pub fn bos(&self) -> Option<&[u8]> {
        self.bos.as_deref()
    }

    /// The device qualifier (high speed only).
    pub fn device_qualifier(&self) -> Option<&[u8]> {
        self.qualifier.as_ref().map(|q| q.as_slice())
    }

    /// The descriptor `GET_DESCRIPTOR` with `wValue = kind << 8 | index` returns in full, if any
    /// (configuration index 0 only).
    pub fn lookup(&self, kind: u8, index: u8) -> Option<&[u8]> {
        match (kind, index) {
            (DEVICE, 0) => Some(self.device()),
            (CONFIGURATION, 0) => Some(self.configuration()),
            (STRING, _) => self.string(index),
            (DEVICE_QUALIFIER, 0) => self.device_qualifier(),
            (BOS, 0) => self.bos(),
            _ => None,
        }
    }

    /// Addresses of the bulk endpoints (bit 7 set for in), in descriptor order.
    pub fn endpoints(&self) -> &[u8] {
        &self.endpoints
    }

    /// Whether `address` is one of the device's bulk endpoints.
    pub fn has_endpoint(&self, address: u8) -> bool {
        self.endpoints.contains(&address)
    }

    /// Interface `number` exists (alternate setting 0 only).
    pub fn has_interface(&self, number: u8) -> bool {
        usize::from(number) < self.spec.interfaces.len()
    }

    /// The interfaces' class triples, for a device list.
    pub fn interface_classes(&self) -> Vec<InterfaceClass> {
        let triple = |i: &InterfaceSpec| InterfaceClass {
            class: i.class,
            subclass: i.subclass,
            protocol: i.protocol,
        };
        self.spec.interfaces.iter().map(triple).collect()
    }

    /// The device record a device list or import reply carries for this device, configured with
    /// `configuration_value` (0: unconfigured).
    pub fn record(
        &self,
        path: SysfsPath,
        busid: BusId,
        busnum: u32,
        devnum: u32,
        configuration_value: u8,
    ) -> DeviceRecord {
        DeviceRecord {
            path,
            busid,
            busnum,
            devnum,
            speed: self.spec.speed.usbip_speed(),
            vendor_id: self.spec.vendor_id,
            product_id: self.spec.product_id,
            bcd_device: self.spec.bcd_device,
            device_class: self.spec.device_class,
            device_subclass: self.spec.device_subclass,
            device_protocol: self.spec.device_protocol,
            configuration_value,
            num_configurations: 1,
            num_interfaces: self.spec.interfaces.len().min(255) as u8,
        }
    }
}

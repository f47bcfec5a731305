//! What a device looks like, in the terms its descriptors are built from.

/// Bus speed the device runs at; it fixes the bulk packet size and which descriptors exist.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Speed {
    /// USB 2.0 high speed: bulk max packet 512 bytes, a device qualifier, no BOS.
    #[default]
    High,
    /// USB 3 SuperSpeed: bulk max packet 1024 bytes, endpoint companions and a BOS descriptor.
    Super,
}

/// One bulk endpoint.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EndpointSpec {
    /// `bEndpointAddress`: number 1-15, bit 7 set for in.
    pub address: u8,
    /// SuperSpeed `bMaxBurst`, 0-15 (packets per burst minus one); ignored at high speed.
    pub max_burst: u8,
}

/// One interface (alternate setting 0) and its bulk endpoints.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct InterfaceSpec {
    /// `bInterfaceClass` (0xff: vendor specific).
    pub class: u8,
    /// `bInterfaceSubClass`.
    pub subclass: u8,
    /// `bInterfaceProtocol`.
    pub protocol: u8,
    /// Interface string (`iInterface`), if any.
    pub name: Option<String>,
    /// Its endpoints, in descriptor order.
    pub endpoints: Vec<EndpointSpec>,
}

/// A device with one configuration (value 1); `DeviceDescriptors::build` turns it into descriptor bytes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DeviceSpec {
    /// Bus speed.
    pub speed: Speed,
    /// `idVendor`.
    pub vendor_id: u16,
    /// `idProduct`.
    pub product_id: u16,
    /// `bcdDevice`, the release number in BCD.
    pub bcd_device: u16,
    /// `bDeviceClass` (0: per interface).
    pub device_class: u8,
    /// `bDeviceSubClass`.
    pub device_subclass: u8,
    /// `bDeviceProtocol`.
    pub device_protocol: u8,
    /// Manufacturer string, if any.
    pub manufacturer: Option<String>,
    /// Product string, if any.
    pub product: Option<String>,
    /// Serial number string, if any.
    pub serial_number: Option<String>,
    /// Self-powered (`bmAttributes` bit 6) rather than bus-powered.
    pub self_powered: bool,
    /// Bus current drawn, in mA (encoded in 2 mA units at high speed, 8 mA at SuperSpeed, saturating).
    pub max_power_ma: u16,
    /// The configuration's interfaces, numbered from 0 in this order.
    pub interfaces: Vec<InterfaceSpec>,
}

impl Speed {
    /// Linux `enum usb_device_speed` value the device record and the vhci attach use: 3 high, 5 super.
    pub fn usbip_speed(self) -> u32 {
        match self {
            Self::High => 3,
            Self::Super => 5,
        }
    }

    /// `wMaxPacketSize` of a bulk endpoint, in bytes.
    pub fn bulk_max_packet(self) -> u16 {
        match self {
            Self::High => 512,
            Self::Super => 1024,
        }
    }
}

impl EndpointSpec {
    /// Bulk in endpoint `number` (1-15), no bursting.
    pub fn bulk_in(number: u8) -> Self {
        Self {
            address: 0x80 | number,
            max_burst: 0,
        }
    }

    /// Bulk out endpoint `number` (1-15), no bursting.
    pub fn bulk_out(number: u8) -> Self {
        Self {
            address: number,
            max_burst: 0,
        }
    }

    /// The same endpoint with a SuperSpeed burst of `max_burst + 1` packets.
    pub fn with_max_burst(self, max_burst: u8) -> Self {
        Self { max_burst, ..self }
    }
}

impl DeviceSpec {
    /// A bus-powered (500 mA) device of class 0 with no strings and no interfaces yet.
    pub fn new(speed: Speed, vendor_id: u16, product_id: u16) -> Self {
        Self {
            speed,
            vendor_id,
            product_id,
            bcd_device: 0x0100,
            device_class: 0,
            device_subclass: 0,
            device_protocol: 0,
            manufacturer: None,
            product: None,
            serial_number: None,
            self_powered: false,
            max_power_ma: 500,
            interfaces: Vec::new(),
        }
    }

    /// The same device with manufacturer, product and serial number strings.
    pub fn with_strings(self, manufacturer: &str, product: &str, serial_number: &str) -> Self {
        Self {
            manufacturer: Some(manufacturer.to_owned()),
            product: Some(product.to_owned()),
            serial_number: Some(serial_number.to_owned()),
            ..self
        }
    }

    /// The same device with one more interface.
    pub fn with_interface(mut self, interface: InterfaceSpec) -> Self {
        self.interfaces.push(interface);
        self
    }
}

//! The 8-byte control setup packet carried in `CMD_SUBMIT` (USB byte order: little-endian).

/// A USB control request's setup stage.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SetupPacket {
    /// `bmRequestType`: bit 7 direction (1: device to host), bits 5-6 type, bits 0-4 recipient.
    pub request_type: u8,
    /// `bRequest`.
    pub request: u8,
    /// `wValue`.
    pub value: u16,
    /// `wIndex`.
    pub index: u16,
    /// `wLength`: bytes of the data stage (the most the host accepts for an in request).
    pub length: u16,
}

/// Request type bits 5-6 of `bmRequestType`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RequestKind {
    /// Standard (chapter 9) request.
    Standard,
    /// Class request.
    Class,
    /// Vendor request.
    Vendor,
    /// Reserved type value 3.
    Reserved,
}

/// Recipient bits 0-4 of `bmRequestType`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Recipient {
    /// The device.
    Device,
    /// An interface (`wIndex` low byte).
    Interface,
    /// An endpoint (`wIndex` low byte, an endpoint address).
    Endpoint,
    /// Other or reserved recipients.
    Other,
}

impl SetupPacket {
    /// Reads the setup field of a `CMD_SUBMIT`.
    pub fn from_bytes(bytes: [u8; 8]) -> Self {
        Self {
            request_type: bytes[0],
            request: bytes[1],
            value: u16::from_le_bytes([bytes[2], bytes[3]]),
            index: u16::from_le_bytes([bytes[4], bytes[5]]),
            length: u16::from_le_bytes([bytes[6], bytes[7]]),
        }
    }

    /// The 8 bytes for a `CMD_SUBMIT`.
    pub fn to_bytes(self) -> [u8; 8] {
        let [v0, v1] = self.value.to_le_bytes();
        let [i0, i1] = self.index.to_le_bytes();
        let [l0, l1] = self.length.to_le_bytes();
        [self.request_type, self.request, v0, v1, i0, i1, l0, l1]
    }

    /// True when the data stage goes device to host.
    pub fn is_in(self) -> bool {
        self.request_type & 0x80 != 0
    }

    /// Standard, class or vendor request.
    pub fn kind(self) -> RequestKind {
        match (self.request_type >> 5) & 0b11 {
            0 => RequestKind::Standard,
            1 => RequestKind::Class,
            2 => RequestKind::Vendor,
            _ => RequestKind::Reserved,
        }
    }

    /// Who the request addresses.
    pub fn recipient(self) -> Recipient {
        match self.request_type & 0x1f {
            0 => Recipient::Device,
            1 => Recipient::Interface,
            2 => Recipient::Endpoint,
            _ => Recipient::Other,
        }
    }
}

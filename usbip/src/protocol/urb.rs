//! The 48-byte URB headers exchanged once a device is imported: submit and unlink, and their returns.

use super::error::DecodeError;
use super::wire::Reader;

/// Command code of `USBIP_CMD_SUBMIT`.
pub const USBIP_CMD_SUBMIT: u32 = 1;
/// Command code of `USBIP_CMD_UNLINK`.
pub const USBIP_CMD_UNLINK: u32 = 2;
/// Command code of `USBIP_RET_SUBMIT`.
pub const USBIP_RET_SUBMIT: u32 = 3;
/// Command code of `USBIP_RET_UNLINK`.
pub const USBIP_RET_UNLINK: u32 = 4;
/// Bytes of every URB header.
pub const URB_HEADER_LEN: usize = 48;
/// Cap on a transfer length (`transfer_buffer_length`, `actual_length`), in bytes: 16 MiB. Longer values
/// are rejected as `TooLarge` before anything is allocated for them.
pub const MAX_TRANSFER_LENGTH: u32 = 16 << 20;
/// Cap on isochronous packets per URB (the kernel's `USBIP_MAX_ISO_PACKETS`).
pub const MAX_ISO_PACKETS: u32 = 1024;
/// Bytes of one isochronous packet descriptor following the data of an isochronous URB.
pub const ISO_PACKET_DESCRIPTOR_LEN: usize = 16;
/// `number_of_packets` of a URB that is not isochronous, as the protocol document gives it (0 is seen too).
pub const NOT_ISOCHRONOUS: u32 = 0xffff_ffff;

/// Direction of a transfer, seen from the host.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Direction {
    /// Host to device (0).
    #[default]
    Out,
    /// Device to host (1).
    In,
}

/// The fields every URB header starts with (`struct usbip_header_basic`, less the command).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct BasicHeader {
    /// Sequence number the host gave the request; returns carry the request's.
    pub seqnum: u32,
    /// Target device, `busnum << 16 | devnum`; 0 in returns.
    pub devid: u32,
    /// Transfer direction; 0 (out) in returns.
    pub direction: Direction,
    /// Endpoint number 0-15, without the direction bit; 0 in returns.
    pub endpoint: u32,
}

/// `USBIP_CMD_SUBMIT`: the host submits a URB. Out data (`transfer_buffer_length` bytes) follows the header.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CmdSubmit {
    /// Sequence number, device, direction, endpoint.
    pub basic: BasicHeader,
    /// Linux URB transfer flags (`URB_SHORT_NOT_OK`, `URB_ZERO_PACKET`, ...).
    pub transfer_flags: u32,
    /// Bytes to send (out) or the most bytes to receive (in); at most `MAX_TRANSFER_LENGTH`.
    pub transfer_buffer_length: u32,
    /// First frame of an isochronous transfer.
    pub start_frame: i32,
    /// Isochronous packets (at most `MAX_ISO_PACKETS`), or 0 / `NOT_ISOCHRONOUS`.
    pub number_of_packets: u32,
    /// Polling interval of an interrupt or isochronous endpoint.
    pub interval: u32,
    /// The control setup packet (USB byte order); zero for other transfers.
    pub setup: [u8; 8],
}

/// `USBIP_CMD_UNLINK`: the host cancels the request with sequence number `unlink_seqnum`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CmdUnlink {
    /// This command's own sequence number, device, direction, endpoint.
    pub basic: BasicHeader,
    /// Sequence number of the request to cancel.
    pub unlink_seqnum: u32,
}

/// `USBIP_RET_SUBMIT`: a request completed. In data (`actual_length` bytes) follows the header.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct RetSubmit {
    /// The request's sequence number; the other basic fields are 0.
    pub basic: BasicHeader,
    /// 0 or a negative Linux errno (`-EPIPE` -32: stall).
    pub status: i32,
    /// Bytes transferred; at most `MAX_TRANSFER_LENGTH`.
    pub actual_length: u32,
    /// First frame of an isochronous transfer.
    pub start_frame: i32,
    /// Isochronous packets, or 0 / `NOT_ISOCHRONOUS`.
    pub number_of_packets: u32,
    /// Isochronous packets that failed.
    pub error_count: u32,
}

/// `USBIP_RET_UNLINK`: the answer to an unlink.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct RetUnlink {
    /// The unlink command's sequence number; the other basic fields are 0.
    pub basic: BasicHeader,
    /// `-ECONNRESET` (-104) when the request was cancelled, 0 when it had already completed.
    pub status: i32,
}

/// Any of the four URB messages, as its 48-byte header.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UrbMessage {
    /// `USBIP_CMD_SUBMIT`.
    CmdSubmit(CmdSubmit),
    /// `USBIP_CMD_UNLINK`.
    CmdUnlink(CmdUnlink),
    /// `USBIP_RET_SUBMIT`.
    RetSubmit(RetSubmit),
    /// `USBIP_RET_UNLINK`.
    RetUnlink(RetUnlink),
}

impl Direction {
    /// The wire value: 0 out, 1 in.
    pub fn to_wire(self) -> u32 {
        match self {
            Self::Out => 0,
            Self::In => 1,
        }
    }

    /// Reads a wire value; anything but 0 or 1 is `BadDirection`.
    pub fn from_wire(value: u32) -> Result<Self, DecodeError> {
        match value {
            0 => Ok(Self::Out),
            1 => Ok(Self::In),
            other => Err(DecodeError::BadDirection(other)),
        }
    }
}

/// Isochronous packets a `number_of_packets` field announces (0 for `NOT_ISOCHRONOUS`).
pub fn iso_packet_count(number_of_packets: u32) -> u32 {
    if number_of_packets == NOT_ISOCHRONOUS {
        0
    } else {
        number_of_packets
    }
}

fn check_length(what: &'static str, value: u32) -> Result<u32, DecodeError> {
    if value > MAX_TRANSFER_LENGTH {
        return Err(DecodeError::TooLarge {
            what,
            value,
            max: MAX_TRANSFER_LENGTH,
        });
    }
    Ok(value)
}

fn check_packets(value: u32) -> Result<u32, DecodeError> {
    if iso_packet_count(value) > MAX_ISO_PACKETS {
        return Err(DecodeError::TooLarge {
            what: "number_of_packets",
            value,
            max: MAX_ISO_PACKETS,
        });
    }
    Ok(value)
}

impl CmdSubmit {
    /// Bytes following the header: out data, then isochronous packet descriptors.
    pub fn payload_len(&self) -> usize {
        let data = match self.basic.direction {
            Direction::Out => self.transfer_buffer_length as usize,
            Direction::In => 0,
        };
        data + iso_packet_count(self.number_of_packets) as usize * ISO_PACKET_DESCRIPTOR_LEN
    }
}

impl RetSubmit {
    /// Bytes following the header, given the direction of the request it answers (returns carry 0 there):
    /// in data, then isochronous packet descriptors.
    pub fn payload_len(&self, request_direction: Direction) -> usize {
        let data = match request_direction {
            Direction::In => self.actual_length as usize,
            Direction::Out => 0,
        };
        data + iso_packet_count(self.number_of_packets) as usize * ISO_PACKET_DESCRIPTOR_LEN
    }
}

impl UrbMessage {
    /// The 48-byte header; unused tail bytes are zero.
    pub fn encode_header(&self) -> [u8; URB_HEADER_LEN] {
        let (command, basic, words): (u32, &BasicHeader, [u32; 5]) = match self {
            Self::CmdSubmit(m) => (
                USBIP_CMD_SUBMIT,
                &m.basic,
                [
                    m.transfer_flags,
                    m.transfer_buffer_length,
                    m.start_frame as u32,
                    m.number_of_packets,
                    m.interval,
                ],
            ),
            Self::CmdUnlink(m) => (USBIP_CMD_UNLINK, &m.basic, [m.unlink_seqnum, 0, 0, 0, 0]),
            Self::RetSubmit(m) => (
                USBIP_RET_SUBMIT,
                &m.basic,
                [
                    m.status as u32,
                    m.actual_length,
                    m.start_frame as u32,
                    m.number_of_packets,
                    m.error_count,
                ],
            ),
            Self::RetUnlink(m) => (USBIP_RET_UNLINK, &m.basic, [m.status as u32, 0, 0, 0, 0]),
        };
        let mut out = [0; URB_HEADER_LEN];
        let leading = [
            command,
            basic.seqnum,
            basic.devid,
            basic.direction.to_wire(),
            basic.endpoint,
        ];
        for (slot, word) in out.chunks_exact_mut(4).zip(leading.iter().chain(&words)) {
            slot.copy_from_slice(&word.to_be_bytes());
        }
        if let Self::CmdSubmit(m) = self {
            out[40..].copy_from_slice(&m.setup);
        }
        out
    }

    /// The header followed by `payload` (out data of a submit, in data of a return).
    pub fn encode(&self, payload: &[u8]) -> Vec<u8> {
        let mut out = Vec::with_capacity(URB_HEADER_LEN + payload.len());
        out.extend_from_slice(&self.encode_header());
        out.extend_from_slice(payload);
        out
    }

    /// Decodes the 48-byte header at the front of `bytes` (any payload after it is left alone).
    pub fn decode_header(bytes: &[u8]) -> Result<Self, DecodeError> {
        let mut reader = Reader::new(bytes, "URB header");
        reader.require(URB_HEADER_LEN)?;
        let command = reader.u32()?;
        let basic = BasicHeader {
            seqnum: reader.u32()?,
            devid: reader.u32()?,
            direction: Direction::from_wire(reader.u32()?)?,
            endpoint: reader.u32()?,
        };
        let message = match command {
            USBIP_CMD_SUBMIT => Self::CmdSubmit(CmdSubmit {
                basic,
                transfer_flags: reader.u32()?,
                transfer_buffer_length: check_length("transfer_buffer_length", reader.u32()?)?,
                start_frame: reader.i32()?,
                number_of_packets: check_packets(reader.u32()?)?,
                interval: reader.u32()?,
                setup: reader.array()?,
            }),
            USBIP_CMD_UNLINK => Self::CmdUnlink(CmdUnlink {
                basic,
                unlink_seqnum: reader.u32()?,
            }),
            USBIP_RET_SUBMIT => Self::RetSubmit(RetSubmit {
                basic,
                status: reader.i32()?,
                actual_length: check_length("actual_length", reader.u32()?)?,
                start_frame: reader.i32()?,
                number_of_packets: check_packets(reader.u32()?)?,
                error_count: reader.u32()?,
            }),
            USBIP_RET_UNLINK => Self::RetUnlink(RetUnlink {
                basic,
                status: reader.i32()?,
            }),
            other => return Err(DecodeError::UnknownCommand(other)),
        };
        Ok(message)
    }
}

//! USB/IP messages as typed values: encoding and decoding only, no I/O. All fields big-endian, version
//! 0x0111 (Linux `Documentation/usb/usbip_protocol.rst`).

mod error;
mod names;
mod op;
mod setup;
mod urb;
mod wire;

pub use error::DecodeError;
pub use names::{BusId, FixedName, NameError, SysfsPath};
pub use op::{
    DEVICE_RECORD_LEN, DeviceRecord, ExportedDevice, INTERFACE_ENTRY_LEN, InterfaceClass,
    OP_HEADER_LEN, OP_REP_DEVLIST, OP_REP_IMPORT, OP_REQ_DEVLIST, OP_REQ_IMPORT, OpKind, OpReply,
    OpRequest, USBIP_VERSION,
};
pub use setup::{Recipient, RequestKind, SetupPacket};
pub use urb::{
    BasicHeader, CmdSubmit, CmdUnlink, Direction, ISO_PACKET_DESCRIPTOR_LEN, MAX_ISO_PACKETS,
    MAX_TRANSFER_LENGTH, NOT_ISOCHRONOUS, RetSubmit, RetUnlink, URB_HEADER_LEN, USBIP_CMD_SUBMIT,
    USBIP_CMD_UNLINK, USBIP_RET_SUBMIT, USBIP_RET_UNLINK, UrbMessage, iso_packet_count,
};

//! Golden byte vectors for every USB/IP message, written from `usbip_protocol.rst`, and the decode errors.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::num::NonZeroU32;

use usbip::protocol::{
    BasicHeader, BusId, CmdSubmit, CmdUnlink, DecodeError, DeviceRecord, Direction, ExportedDevice,
    InterfaceClass, OpKind, OpReply, OpRequest, RetSubmit, RetUnlink, SetupPacket, SysfsPath,
    UrbMessage,
};

fn busid_field(name: &str) -> Vec<u8> {
    let mut field = name.as_bytes().to_vec();
    field.resize(32, 0);
    field
}

fn record() -> DeviceRecord {
    DeviceRecord {
        path: SysfsPath::new("/sys/x").unwrap(),
        busid: BusId::new("1-1").unwrap(),
        busnum: 1,
        devnum: 2,
        speed: 3,
        vendor_id: 0x04b4,
        product_id: 0x00f5,
        bcd_device: 0x0100,
        device_class: 0xef,
        device_subclass: 2,
        device_protocol: 1,
        configuration_value: 1,
        num_configurations: 1,
        num_interfaces: 1,
    }
}

fn record_bytes() -> Vec<u8> {
    let mut out = b"/sys/x".to_vec();
    out.resize(256, 0);
    out.extend(busid_field("1-1"));
    out.extend([0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0, 3]);
    out.extend([0x04, 0xb4, 0x00, 0xf5, 0x01, 0x00]);
    out.extend([0xef, 2, 1, 1, 1, 1]);
    out
}

#[test]
fn op_req_devlist_is_version_code_status() {
    let bytes = [0x01, 0x11, 0x80, 0x05, 0, 0, 0, 0];
    assert_eq!(OpRequest::DevList.encode(), bytes);
    assert_eq!(OpRequest::decode(&bytes).unwrap(), (OpRequest::DevList, 8));
}

#[test]
fn op_req_import_carries_a_32_byte_busid() {
    let mut bytes = vec![0x01, 0x11, 0x80, 0x03, 0, 0, 0, 0];
    bytes.extend(busid_field("1-1"));
    let request = OpRequest::Import(BusId::new("1-1").unwrap());
    assert_eq!(request.encode(), bytes);
    assert_eq!(OpRequest::decode(&bytes).unwrap(), (request, 40));
}

#[test]
fn op_rep_import_is_header_then_0x138_byte_record() {
    let mut bytes = vec![0x01, 0x11, 0x00, 0x03, 0, 0, 0, 0];
    bytes.extend(record_bytes());
    assert_eq!(bytes.len(), 8 + 0x138);
    assert_eq!(OpReply::Imported(record()).encode(), bytes);
    assert_eq!(
        OpReply::decode(&bytes).unwrap(),
        (OpReply::Imported(record()), 8 + 0x138)
    );
    assert_eq!(record().devid(), 0x0001_0002);
}

#[test]
fn refused_import_is_the_header_alone_with_status_1() {
    let bytes = [0x01, 0x11, 0x00, 0x03, 0, 0, 0, 1];
    let refused = OpReply::Refused {
        kind: OpKind::Import,
        status: NonZeroU32::MIN,
    };
    assert_eq!(refused.encode(), bytes);
    assert_eq!(OpReply::decode(&bytes).unwrap(), (refused, 8));
}

#[test]
fn op_rep_devlist_lists_records_each_followed_by_interface_triples() {
    let mut bytes = vec![0x01, 0x11, 0x00, 0x05, 0, 0, 0, 0, 0, 0, 0, 1];
    bytes.extend(record_bytes());
    bytes.extend([0xff, 0x00, 0x01, 0x00]);
    let device = ExportedDevice {
        record: record(),
        interfaces: vec![InterfaceClass {
            class: 0xff,
            subclass: 0,
            protocol: 1,
        }],
    };
    let reply = OpReply::DevList(vec![device]);
    assert_eq!(reply.encode(), bytes);
    assert_eq!(OpReply::decode(&bytes).unwrap(), (reply, bytes.len()));
}

#[test]
fn cmd_submit_header_fields_in_order_then_setup() {
    let bytes = [
        0, 0, 0, 1, 0, 0, 0, 0x0a, 0, 1, 0, 2, 0, 0, 0, 1, 0, 0, 0,
        0, // command, seqnum, devid, direction, ep
        0, 0, 2, 0, 0, 0, 0, 0x12, 0, 0, 0, 0, 0xff, 0xff, 0xff, 0xff, 0, 0, 0,
        0, // flags .. interval
        0x80, 0x06, 0x00, 0x01, 0x00, 0x00, 0x12,
        0x00, // setup: GET_DESCRIPTOR(device), wLength 18
    ];
    let setup = SetupPacket {
        request_type: 0x80,
        request: 6,
        value: 0x0100,
        index: 0,
        length: 18,
    };
    let message = UrbMessage::CmdSubmit(CmdSubmit {
        basic: BasicHeader {
            seqnum: 10,
            devid: 0x0001_0002,
            direction: Direction::In,
            endpoint: 0,
        },
        transfer_flags: 0x200,
        transfer_buffer_length: 18,
        start_frame: 0,
        number_of_packets: 0xffff_ffff,
        interval: 0,
        setup: setup.to_bytes(),
    });
    assert_eq!(message.encode_header(), bytes);
    assert_eq!(UrbMessage::decode_header(&bytes).unwrap(), message);
    assert_eq!(SetupPacket::from_bytes(setup.to_bytes()), setup);
}

#[test]
fn cmd_submit_out_is_followed_by_its_data() {
    let command = CmdSubmit {
        basic: BasicHeader {
            seqnum: 1,
            devid: 0,
            direction: Direction::Out,
            endpoint: 2,
        },
        transfer_buffer_length: 3,
        ..CmdSubmit::default()
    };
    assert_eq!(command.payload_len(), 3);
    let bytes = UrbMessage::CmdSubmit(command).encode(&[7, 8, 9]);
    assert_eq!(bytes.len(), 51);
    assert_eq!(&bytes[48..], &[7, 8, 9]);
    assert_eq!(&bytes[24..28], &[0, 0, 0, 3]);
}

#[test]
fn ret_submit_status_length_and_zero_padding() {
    let mut bytes = vec![
        0, 0, 0, 3, 0, 0, 0, 0x0a, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
    ];
    bytes.extend([
        0xff, 0xff, 0xff, 0xe0, 0, 0, 0, 4, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
    ]);
    bytes.extend([0; 8]);
    let message = RetSubmit {
        basic: BasicHeader {
            seqnum: 10,
            ..BasicHeader::default()
        },
        status: -32,
        actual_length: 4,
        ..RetSubmit::default()
    };
    assert_eq!(
        UrbMessage::RetSubmit(message).encode_header().to_vec(),
        bytes
    );
    assert_eq!(
        UrbMessage::decode_header(&bytes).unwrap(),
        UrbMessage::RetSubmit(message)
    );
    assert_eq!(message.payload_len(Direction::In), 4);
    assert_eq!(message.payload_len(Direction::Out), 0);
}

#[test]
fn cmd_unlink_and_ret_unlink() {
    let mut unlink = vec![
        0, 0, 0, 2, 0, 0, 0, 0x0b, 0, 1, 0, 2, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 0x0a,
    ];
    unlink.resize(48, 0);
    let command = CmdUnlink {
        basic: BasicHeader {
            seqnum: 11,
            devid: 0x0001_0002,
            direction: Direction::In,
            endpoint: 1,
        },
        unlink_seqnum: 10,
    };
    assert_eq!(
        UrbMessage::CmdUnlink(command).encode_header().to_vec(),
        unlink
    );
    assert_eq!(
        UrbMessage::decode_header(&unlink).unwrap(),
        UrbMessage::CmdUnlink(command)
    );

    let mut ret = vec![
        0, 0, 0, 4, 0, 0, 0, 0x0b, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0xff, 0xff, 0xff, 0x98,
    ];
    ret.resize(48, 0);
    let answer = RetUnlink {
        basic: BasicHeader {
            seqnum: 11,
            ..BasicHeader::default()
        },
        status: -104,
    };
    assert_eq!(UrbMessage::RetUnlink(answer).encode_header().to_vec(), ret);
    assert_eq!(
        UrbMessage::decode_header(&ret).unwrap(),
        UrbMessage::RetUnlink(answer)
    );
}

#[test]
fn decode_errors_name_what_is_wrong() {
    assert_eq!(
        OpRequest::decode(&[0x01, 0x06, 0x80, 0x05, 0, 0, 0, 0]),
        Err(DecodeError::BadVersion(0x0106))
    );
    assert_eq!(
        OpRequest::decode(&[0x01, 0x11, 0x80, 0x07, 0, 0, 0, 0]),
        Err(DecodeError::UnknownOpCode(0x8007))
    );
    assert_eq!(
        OpRequest::decode(&[0x01, 0x11, 0x80, 0x03, 0, 0, 0, 0, b'1']),
        Err(DecodeError::Truncated {
            what: "operation request",
            needed: 40,
            available: 9
        })
    );
    let mut unterminated = vec![0x01, 0x11, 0x80, 0x03, 0, 0, 0, 0];
    unterminated.extend([b'x'; 32]);
    assert_eq!(
        OpRequest::decode(&unterminated),
        Err(DecodeError::BadString("busid"))
    );

    let mut header = [0u8; 48];
    header[3] = 9;
    assert_eq!(
        UrbMessage::decode_header(&header),
        Err(DecodeError::UnknownCommand(9))
    );
    header[3] = 1;
    header[15] = 2;
    assert_eq!(
        UrbMessage::decode_header(&header),
        Err(DecodeError::BadDirection(2))
    );
    header[15] = 0;
    header[24..28].copy_from_slice(&(16u32 << 20 | 1).to_be_bytes());
    assert!(matches!(
        UrbMessage::decode_header(&header),
        Err(DecodeError::TooLarge {
            what: "transfer_buffer_length",
            value: 0x0100_0001,
            ..
        })
    ));
    assert!(matches!(
        UrbMessage::decode_header(&header[..47]),
        Err(DecodeError::Truncated { needed: 48, .. })
    ));
}

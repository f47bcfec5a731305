//! Property tests: every message round-trips, strict prefixes report truncation, and decoding arbitrary
//! bytes never panics.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use proptest::prelude::*;
use usbip::protocol::{
    BasicHeader, BusId, CmdSubmit, CmdUnlink, DecodeError, DeviceRecord, Direction, ExportedDevice,
    InterfaceClass, MAX_ISO_PACKETS, MAX_TRANSFER_LENGTH, NOT_ISOCHRONOUS, OpKind, OpReply,
    OpRequest, RetSubmit, RetUnlink, SetupPacket, SysfsPath, UrbMessage,
};

fn direction() -> impl Strategy<Value = Direction> {
    prop_oneof![Just(Direction::Out), Just(Direction::In)]
}

fn basic() -> impl Strategy<Value = BasicHeader> {
    (any::<u32>(), any::<u32>(), direction(), 0u32..16).prop_map(
        |(seqnum, devid, direction, endpoint)| BasicHeader {
            seqnum,
            devid,
            direction,
            endpoint,
        },
    )
}

fn length() -> impl Strategy<Value = u32> {
    prop_oneof![0..=4096u32, 0..=MAX_TRANSFER_LENGTH]
}

fn packets() -> impl Strategy<Value = u32> {
    prop_oneof![Just(0), Just(NOT_ISOCHRONOUS), 0..=MAX_ISO_PACKETS]
}

fn urb_message() -> impl Strategy<Value = UrbMessage> {
    let submit = (
        basic(),
        any::<u32>(),
        length(),
        any::<i32>(),
        packets(),
        any::<u32>(),
        any::<[u8; 8]>(),
    )
        .prop_map(
            |(
                basic,
                transfer_flags,
                transfer_buffer_length,
                start_frame,
                number_of_packets,
                interval,
                setup,
            )| {
                UrbMessage::CmdSubmit(CmdSubmit {
                    basic,
                    transfer_flags,
                    transfer_buffer_length,
                    start_frame,
                    number_of_packets,
                    interval,
                    setup,
                })
            },
        );
    let unlink = (basic(), any::<u32>()).prop_map(|(basic, unlink_seqnum)| {
        UrbMessage::CmdUnlink(CmdUnlink {
            basic,
            unlink_seqnum,
        })
    });
    let ret = (
        basic(),
        any::<i32>(),
        length(),
        any::<i32>(),
        packets(),
        any::<u32>(),
    )
        .prop_map(
            |(basic, status, actual_length, start_frame, number_of_packets, error_count)| {
                UrbMessage::RetSubmit(RetSubmit {
                    basic,
                    status,
                    actual_length,
                    start_frame,
                    number_of_packets,
                    error_count,
                })
            },
        );
    let ret_unlink = (basic(), any::<i32>())
        .prop_map(|(basic, status)| UrbMessage::RetUnlink(RetUnlink { basic, status }));
    prop_oneof![submit, unlink, ret, ret_unlink]
}

fn busid() -> impl Strategy<Value = BusId> {
    "[0-9a-z.:-]{0,31}".prop_map(|s| BusId::new(&s).unwrap())
}

fn record() -> impl Strategy<Value = DeviceRecord> {
    let path = "[ -~]{0,255}".prop_map(|s| SysfsPath::new(&s).unwrap());
    let numbers = (
        any::<u32>(),
        any::<u32>(),
        any::<u32>(),
        any::<u16>(),
        any::<u16>(),
        any::<u16>(),
    );
    (path, busid(), numbers, any::<[u8; 6]>()).prop_map(|(path, busid, n, b)| DeviceRecord {
        path,
        busid,
        busnum: n.0,
        devnum: n.1,
        speed: n.2,
        vendor_id: n.3,
        product_id: n.4,
        bcd_device: n.5,
        device_class: b[0],
        device_subclass: b[1],
        device_protocol: b[2],
        configuration_value: b[3],
        num_configurations: b[4],
        num_interfaces: b[5],
    })
}

fn exported() -> impl Strategy<Value = ExportedDevice> {
    let interface = any::<[u8; 3]>().prop_map(|[class, subclass, protocol]| InterfaceClass {
        class,
        subclass,
        protocol,
    });
    (record(), prop::collection::vec(interface, 0..6)).prop_map(|(mut record, interfaces)| {
        record.num_interfaces = interfaces.len() as u8;
        ExportedDevice { record, interfaces }
    })
}

fn op_reply() -> impl Strategy<Value = OpReply> {
    let kind = prop_oneof![Just(OpKind::DevList), Just(OpKind::Import)];
    prop_oneof![
        prop::collection::vec(exported(), 0..3).prop_map(OpReply::DevList),
        record().prop_map(OpReply::Imported),
        (kind, 1u32..).prop_map(|(kind, status)| OpReply::Refused {
            kind,
            status: status.try_into().unwrap()
        }),
    ]
}

proptest! {
    #[test]
    fn urb_headers_round_trip(message in urb_message()) {
        let header = message.encode_header();
        prop_assert_eq!(UrbMessage::decode_header(&header), Ok(message));
        for cut in 0..header.len() {
            let truncated = matches!(UrbMessage::decode_header(&header[..cut]), Err(DecodeError::Truncated { .. }));
            prop_assert!(truncated);
        }
    }

    #[test]
    fn op_requests_round_trip(import in any::<bool>(), busid in busid()) {
        let request = if import { OpRequest::Import(busid) } else { OpRequest::DevList };
        let bytes = request.encode();
        prop_assert_eq!(OpRequest::decode(&bytes), Ok((request, bytes.len())));
    }

    #[test]
    fn op_replies_round_trip_and_prefixes_are_truncated(reply in op_reply()) {
        let bytes = reply.encode();
        prop_assert_eq!(OpReply::decode(&bytes), Ok((reply, bytes.len())));
        for cut in (0..bytes.len()).step_by(7) {
            let result = OpReply::decode(&bytes[..cut]);
            let truncated = matches!(result, Err(DecodeError::Truncated { needed, .. }) if needed > cut);
            prop_assert!(truncated);
        }
    }

    #[test]
    fn setup_packets_round_trip(bytes in any::<[u8; 8]>()) {
        prop_assert_eq!(SetupPacket::from_bytes(bytes).to_bytes(), bytes);
    }

    #[test]
    fn decoding_arbitrary_bytes_never_panics(bytes in prop::collection::vec(any::<u8>(), 0..400)) {
        let _ = OpRequest::decode(&bytes);
        let _ = OpReply::decode(&bytes);
        let _ = UrbMessage::decode_header(&bytes);
    }

    #[test]
    fn decoding_bytes_behind_valid_headers_never_panics(
        code in prop_oneof![Just(0x8005u16), Just(0x8003), Just(0x0005), Just(0x0003)],
        command in 0u32..6,
        tail in prop::collection::vec(any::<u8>(), 0..700),
    ) {
        let mut op = vec![0x01, 0x11];
        op.extend(code.to_be_bytes());
        op.extend([0, 0, 0, 0]);
        op.extend(&tail);
        let _ = OpRequest::decode(&op);
        let _ = OpReply::decode(&op);
        let mut urb = command.to_be_bytes().to_vec();
        urb.extend(&tail);
        if let Ok(UrbMessage::CmdSubmit(submit)) = UrbMessage::decode_header(&urb) {
            prop_assert!(submit.payload_len() <= MAX_TRANSFER_LENGTH as usize + 16 * MAX_ISO_PACKETS as usize);
        }
    }
}

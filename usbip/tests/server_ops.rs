//! The server's operation phase, standard control requests and disconnect, against a test client.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use common::{Client, VENDOR_IN, device_spec, get_descriptor, start, wait_until};
use usbip::descriptors::DeviceDescriptors;
use usbip::protocol::{BusId, Direction, OpKind, OpReply, OpRequest, SetupPacket};

#[test]
fn devlist_lists_the_device_and_closes() {
    let (server, _) = start();
    let mut client = Client::connect(server.local_addr());
    let OpReply::DevList(devices) = client.operation(&OpRequest::DevList) else {
        panic!("not a device list")
    };
    assert_eq!(devices.len(), 1);
    let record = &devices[0].record;
    assert_eq!(
        (record.busid.as_str(), record.vendor_id, record.product_id),
        ("1-1", 0x1209, 0x0001)
    );
    assert_eq!(
        (record.speed, record.num_interfaces, record.devid()),
        (3, 1, 0x0001_0002)
    );
    assert_eq!(devices[0].interfaces[0].class, 0xff);
    assert!(client.is_closed());
}

#[test]
fn import_refuses_unknown_busid_and_a_second_host() {
    let (server, _) = start();
    let mut stranger = Client::connect(server.local_addr());
    let reply = stranger.operation(&OpRequest::Import(BusId::new("2-1").unwrap()));
    assert!(
        matches!(reply, OpReply::Refused { kind: OpKind::Import, status } if status.get() == 1)
    );
    assert!(!server.is_attached());

    let mut first = Client::connect(server.local_addr());
    let OpReply::Imported(record) = first.operation(&OpRequest::Import(BusId::new("1-1").unwrap()))
    else {
        panic!("import refused")
    };
    assert_eq!(record.busid.as_str(), "1-1");
    assert!(server.is_attached());
    let mut second = Client::connect(server.local_addr());
    let reply = second.operation(&OpRequest::Import(BusId::new("1-1").unwrap()));
    assert!(matches!(reply, OpReply::Refused { .. }));
}

#[test]
fn get_descriptor_answers_device_configuration_and_strings_cut_to_wlength() {
    let (server, _) = start();
    let expected = DeviceDescriptors::build(&device_spec()).unwrap();
    let mut client = Client::attach(server.local_addr());
    client.control_in(1, get_descriptor(1, 0, 18));
    assert_eq!(client.expect_submit(1), (0, expected.device().to_vec()));
    client.control_in(2, get_descriptor(2, 0, 9));
    let (status, head) = client.expect_submit(2);
    assert_eq!((status, head.len(), head[2]), (0, 9, 32));
    client.control_in(3, get_descriptor(2, 0, 255));
    assert_eq!(
        client.expect_submit(3),
        (0, expected.configuration().to_vec())
    );
    client.control_in(4, get_descriptor(3, 0, 255));
    assert_eq!(client.expect_submit(4), (0, vec![4, 3, 0x09, 0x04]));
    client.control_in(5, get_descriptor(3, 2, 255));
    let (_, product) = client.expect_submit(5);
    let units: Vec<u16> = product[2..]
        .chunks(2)
        .map(|c| u16::from_le_bytes([c[0], c[1]]))
        .collect();
    assert_eq!(String::from_utf16(&units).unwrap(), "Test camera");
    client.control_in(6, get_descriptor(0x0f, 0, 5));
    assert_eq!(
        client.expect_submit(6).0,
        -32,
        "a high-speed device has no BOS"
    );
    client.control_in(7, get_descriptor(3, 9, 255));
    assert_eq!(client.expect_submit(7).0, -32);
}

#[test]
fn configuration_status_and_vendor_requests() {
    let (server, script) = start();
    let mut client = Client::attach(server.local_addr());
    let set_configuration = SetupPacket {
        request_type: 0,
        request: 9,
        value: 1,
        index: 0,
        length: 0,
    };
    client.submit(1, Direction::Out, 0, 0, set_configuration.to_bytes(), &[]);
    assert_eq!(client.expect_submit(1), (0, vec![]));
    assert_eq!(script.lock().unwrap().configured, [1]);
    client.control_in(
        2,
        SetupPacket {
            request_type: 0x80,
            request: 8,
            value: 0,
            index: 0,
            length: 1,
        },
    );
    assert_eq!(client.expect_submit(2), (0, vec![1]));
    let bad = SetupPacket {
        value: 7,
        ..set_configuration
    };
    client.submit(3, Direction::Out, 0, 0, bad.to_bytes(), &[]);
    assert_eq!(client.expect_submit(3).0, -32);
    client.control_in(
        4,
        SetupPacket {
            request_type: 0x80,
            request: 0,
            value: 0,
            index: 0,
            length: 2,
        },
    );
    assert_eq!(client.expect_submit(4), (0, vec![0, 0]));
    client.control_in(
        5,
        SetupPacket {
            request_type: 0xc0,
            request: VENDOR_IN,
            value: 0,
            index: 0,
            length: 3,
        },
    );
    assert_eq!(
        client.expect_submit(5),
        (0, vec![1, 2, 3]),
        "vendor data cut to wLength"
    );
    let vendor_out = SetupPacket {
        request_type: 0x40,
        request: 0x43,
        value: 0,
        index: 0,
        length: 2,
    };
    client.submit(6, Direction::Out, 0, 2, vendor_out.to_bytes(), &[9, 8]);
    let (status, data) = client.expect_submit(6);
    assert_eq!((status, data.len()), (0, 0));
    assert_eq!(script.lock().unwrap().received, [vec![9, 8]]);
    let counters = server.counters();
    assert_eq!(
        (counters.submitted, counters.completed, counters.bytes_out),
        (6, 6, 2)
    );
    assert_eq!(counters.bytes_in, 1 + 2 + 3);
}

#[test]
fn disconnect_closes_the_socket_and_frees_the_device() {
    let (server, script) = start();
    let mut client = Client::attach(server.local_addr());
    client.bulk_in(1, 512);
    client.control_in(2, get_descriptor(1, 0, 18));
    client.expect_submit(2);
    assert!(server.disconnect());
    assert!(client.is_closed());
    wait_until("the session to end", || !server.is_attached());
    assert_eq!(script.lock().unwrap().detached, 1);
    assert_eq!(server.counters().pending_in, 0);
    assert!(!server.disconnect());

    let mut again = Client::attach(server.local_addr());
    again.control_in(1, get_descriptor(1, 0, 8));
    assert_eq!(again.expect_submit(1).1.len(), 8);
}

#[test]
fn host_closing_the_socket_detaches_and_stop_ends_the_server() {
    let (server, script) = start();
    let client = Client::attach(server.local_addr());
    drop(client);
    wait_until("the session to end", || !server.is_attached());
    assert_eq!(script.lock().unwrap().detached, 1);
    let addr = server.local_addr();
    server.stop();
    let refused = std::net::TcpStream::connect(addr).is_err();
    assert!(refused, "the listener is closed after stop");
}

//! Bulk transfers through the server: pending bulk-in requests, unlinks, stalls and many queued requests
//! while control traffic goes on.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use std::thread;

use common::{Client, Reply, get_descriptor, start, wait_until};
use usbip::protocol::{Direction, SetupPacket};

#[test]
fn bulk_out_reaches_the_device_and_unknown_endpoints_stall() {
    let (server, script) = start();
    let mut client = Client::attach(server.local_addr());
    client.bulk_out(1, &[1, 2, 3]);
    match client.read_reply() {
        Reply::Submit(ret, data) => {
            assert_eq!((ret.status, ret.actual_length, data.len()), (0, 3, 0))
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(script.lock().unwrap().received, [vec![1, 2, 3]]);
    client.submit(2, Direction::In, 5, 64, [0; 8], &[]);
    assert_eq!(client.expect_submit(2).0, -32);
    client.submit(3, Direction::Out, 1, 1, [0; 8], &[0]);
    assert_eq!(client.expect_submit(3).0, -32, "endpoint 1 is in only");
}

#[test]
fn bulk_in_stays_pending_until_the_device_has_data() {
    let (server, _) = start();
    let mut client = Client::attach(server.local_addr());
    client.bulk_in(10, 512);
    client.control_in(11, get_descriptor(1, 0, 18));
    assert_eq!(
        client.expect_submit(11).0,
        0,
        "the control reply comes first: the bulk-in request waits"
    );
    assert_eq!(server.counters().pending_in, 1);
    server.with_device(|device| {
        device
            .script
            .lock()
            .unwrap()
            .in_data
            .push_back(vec![7; 100])
    });
    assert_eq!(client.expect_submit(10), (0, vec![7; 100]));
    let counters = server.counters();
    assert_eq!(
        (counters.pending_in, counters.completed, counters.bytes_in),
        (0, 2, 118)
    );
}

#[test]
fn unlinking_a_pending_request_answers_econnreset_and_never_completes_it() {
    let (server, _) = start();
    let mut client = Client::attach(server.local_addr());
    client.bulk_in(20, 512);
    client.unlink(21, 20);
    assert_eq!(client.expect_unlink(21), -104);
    client.bulk_in(22, 512);
    server.with_device(|device| device.script.lock().unwrap().in_data.push_back(vec![1]));
    // A RET_SUBMIT for 20 would fail here: the client no longer knows 20 and expects 22.
    assert_eq!(client.expect_submit(22), (0, vec![1]));
    client.control_in(23, get_descriptor(1, 0, 18));
    client.expect_submit(23);
    let counters = server.counters();
    assert_eq!((counters.unlinked, counters.pending_in), (1, 0));
}

#[test]
fn unlinking_a_completed_request_answers_zero() {
    let (server, _) = start();
    let mut client = Client::attach(server.local_addr());
    server.with_device(|device| device.script.lock().unwrap().in_data.push_back(vec![5, 6]));
    client.bulk_in(30, 512);
    assert_eq!(client.expect_submit(30), (0, vec![5, 6]));
    client.unlink(31, 30);
    assert_eq!(client.expect_unlink(31), 0);
    assert_eq!(server.counters().unlinked, 0);
}

#[test]
fn control_is_answered_while_32_bulk_in_requests_wait_and_they_complete_in_order() {
    let (server, script) = start();
    let mut client = Client::attach(server.local_addr());
    for seqnum in 100..132 {
        client.bulk_in(seqnum, 16384);
        if seqnum % 8 == 0 {
            client.control_in(seqnum + 1000, get_descriptor(1, 0, 18));
        }
    }
    for seqnum in [1104, 1112, 1120, 1128] {
        assert_eq!(client.expect_submit(seqnum).0, 0);
    }
    client.control_in(2000, get_descriptor(2, 0, 9));
    assert_eq!(client.expect_submit(2000).0, 0);
    assert_eq!(server.counters().pending_in, 32);

    let waker = server.waker();
    let producer = thread::spawn(move || {
        for chunk in 0..32u8 {
            script.lock().unwrap().in_data.push_back(vec![chunk; 1000]);
            waker.wake();
        }
    });
    for (chunk, seqnum) in (100..132).enumerate() {
        assert_eq!(client.expect_submit(seqnum), (0, vec![chunk as u8; 1000]));
    }
    producer.join().unwrap();
    wait_until("the pending gauge to drop", || {
        server.counters().pending_in == 0
    });
}

#[test]
fn a_stall_halts_the_endpoint_until_the_host_clears_it() {
    let (server, script) = start();
    let mut client = Client::attach(server.local_addr());
    server.with_device(|device| device.script.lock().unwrap().stall_in = true);
    client.bulk_in(1, 512);
    assert_eq!(client.expect_submit(1).0, -32);
    let endpoint_status = SetupPacket {
        request_type: 0x82,
        request: 0,
        value: 0,
        index: 0x81,
        length: 2,
    };
    client.control_in(2, endpoint_status);
    assert_eq!(client.expect_submit(2), (0, vec![1, 0]));
    client.bulk_in(3, 512);
    server.with_device(|device| device.script.lock().unwrap().in_data.push_back(vec![9]));
    client.control_in(4, endpoint_status);
    assert_eq!(
        client.expect_submit(4),
        (0, vec![1, 0]),
        "request 3 waits behind the halt"
    );

    let clear_halt = SetupPacket {
        request_type: 0x02,
        request: 1,
        value: 0,
        index: 0x81,
        length: 0,
    };
    client.submit(5, Direction::Out, 0, 0, clear_halt.to_bytes(), &[]);
    assert_eq!(client.expect_submit(5).0, 0);
    assert_eq!(client.expect_submit(3), (0, vec![9]));
    assert_eq!(script.lock().unwrap().cleared, [0x81]);
    client.control_in(6, endpoint_status);
    assert_eq!(client.expect_submit(6), (0, vec![0, 0]));
}

#[test]
fn data_longer_than_the_request_completes_with_eoverflow() {
    let (server, _) = start();
    let mut client = Client::attach(server.local_addr());
    server.with_device(|device| {
        device
            .script
            .lock()
            .unwrap()
            .in_data
            .push_back(vec![0; 600])
    });
    client.bulk_in(1, 512);
    assert_eq!(client.expect_submit(1), (-75, vec![]));
}

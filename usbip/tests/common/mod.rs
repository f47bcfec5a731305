//! A host-side USB/IP client and a scripted device for the server tests.

#![allow(clippy::unwrap_used, clippy::expect_used, dead_code)]

use std::collections::{HashMap, VecDeque};
use std::io::{ErrorKind, Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use usbip::descriptors::{DeviceDescriptors, DeviceSpec, EndpointSpec, InterfaceSpec, Speed};
use usbip::protocol::{
    BasicHeader, BusId, CmdSubmit, CmdUnlink, DecodeError, Direction, OpReply, OpRequest,
    RetSubmit, RetUnlink, SetupPacket, URB_HEADER_LEN, UrbMessage,
};
use usbip::server::{BulkIn, ServerConfig, ServerHandle, UrbError, UsbDevice, spawn};

/// Failure guard for every read: a hung server fails the test instead of hanging it.
pub const GUARD: Duration = Duration::from_secs(10);
pub const DEVID: u32 = 0x0001_0002;
pub const VENDOR_IN: u8 = 0x42;

/// What the scripted device saw and will answer, shared with the test.
#[derive(Debug, Default)]
pub struct Script {
    pub in_data: VecDeque<Vec<u8>>,
    pub stall_in: bool,
    pub received: Vec<Vec<u8>>,
    pub cleared: Vec<u8>,
    pub configured: Vec<u8>,
    pub detached: usize,
}

pub struct TestDevice {
    pub descriptors: DeviceDescriptors,
    pub script: Arc<Mutex<Script>>,
}

impl UsbDevice for TestDevice {
    fn descriptors(&self) -> &DeviceDescriptors {
        &self.descriptors
    }

    fn control(&mut self, setup: SetupPacket, data_out: &[u8]) -> Result<Vec<u8>, UrbError> {
        match setup.request {
            VENDOR_IN => Ok(vec![1, 2, 3, 4, 5]),
            _ => {
                self.script.lock().unwrap().received.push(data_out.to_vec());
                Ok(Vec::new())
            }
        }
    }

    fn bulk_out(&mut self, _endpoint: u8, data: &[u8]) -> Result<(), UrbError> {
        self.script.lock().unwrap().received.push(data.to_vec());
        Ok(())
    }

    fn bulk_in(&mut self, endpoint: u8, _max_len: usize) -> BulkIn {
        assert_eq!(endpoint, 0x81);
        let mut script = self.script.lock().unwrap();
        if script.stall_in {
            script.stall_in = false;
            return BulkIn::Failed(UrbError::Stall);
        }
        script
            .in_data
            .pop_front()
            .map_or(BulkIn::Pending, BulkIn::Data)
    }

    fn clear_halt(&mut self, endpoint: u8) {
        self.script.lock().unwrap().cleared.push(endpoint);
    }

    fn configured(&mut self, value: u8) {
        self.script.lock().unwrap().configured.push(value);
    }

    fn detached(&mut self) {
        self.script.lock().unwrap().detached += 1;
    }
}

pub fn device_spec() -> DeviceSpec {
    DeviceSpec::new(Speed::High, 0x1209, 0x0001)
        .with_strings("EventTrack6D", "Test camera", "42")
        .with_interface(InterfaceSpec {
            class: 0xff,
            endpoints: vec![EndpointSpec::bulk_in(1), EndpointSpec::bulk_out(2)],
            ..InterfaceSpec::default()
        })
}

/// A server for the test device on a loopback port, and the device's script.
pub fn start() -> (ServerHandle<TestDevice>, Arc<Mutex<Script>>) {
    let script = Arc::new(Mutex::new(Script::default()));
    let device = TestDevice {
        descriptors: DeviceDescriptors::build(&device_spec()).unwrap(),
        script: script.clone(),
    };
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let mut config = ServerConfig::new(BusId::new("1-1").unwrap());
    config.devnum = 2;
    (spawn(listener, device, config).unwrap(), script)
}

/// A reply to a submit or an unlink, with a submit's in data.
#[derive(Debug, PartialEq)]
pub enum Reply {
    Submit(RetSubmit, Vec<u8>),
    Unlink(RetUnlink),
}

/// The host side: operations, then URBs with the direction of every outstanding submit remembered.
pub struct Client {
    stream: TcpStream,
    directions: HashMap<u32, Direction>,
}

impl Client {
    pub fn connect(addr: SocketAddr) -> Self {
        let stream = TcpStream::connect(addr).unwrap();
        stream.set_read_timeout(Some(GUARD)).unwrap();
        Self {
            stream,
            directions: HashMap::new(),
        }
    }

    pub fn operation(&mut self, request: &OpRequest) -> OpReply {
        self.stream.write_all(&request.encode()).unwrap();
        let mut bytes = vec![0; 8];
        self.stream.read_exact(&mut bytes).unwrap();
        loop {
            match OpReply::decode(&bytes) {
                Ok((reply, _)) => return reply,
                Err(DecodeError::Truncated { needed, .. }) => {
                    let have = bytes.len();
                    bytes.resize(needed, 0);
                    self.stream.read_exact(&mut bytes[have..]).unwrap();
                }
                Err(error) => panic!("bad reply: {error}"),
            }
        }
    }

    /// Connects and imports bus id `1-1`, panicking unless the import succeeds.
    pub fn attach(addr: SocketAddr) -> Self {
        let mut client = Self::connect(addr);
        let reply = client.operation(&OpRequest::Import(BusId::new("1-1").unwrap()));
        assert!(
            matches!(reply, OpReply::Imported(_)),
            "import refused: {reply:?}"
        );
        client
    }

    pub fn submit(
        &mut self,
        seqnum: u32,
        direction: Direction,
        endpoint: u32,
        length: u32,
        setup: [u8; 8],
        data: &[u8],
    ) {
        let basic = BasicHeader {
            seqnum,
            devid: DEVID,
            direction,
            endpoint,
        };
        let command = CmdSubmit {
            basic,
            transfer_buffer_length: length,
            setup,
            ..CmdSubmit::default()
        };
        self.directions.insert(seqnum, direction);
        self.stream
            .write_all(&UrbMessage::CmdSubmit(command).encode(data))
            .unwrap();
    }

    pub fn control_in(&mut self, seqnum: u32, setup: SetupPacket) {
        self.submit(
            seqnum,
            Direction::In,
            0,
            u32::from(setup.length),
            setup.to_bytes(),
            &[],
        );
    }

    pub fn bulk_in(&mut self, seqnum: u32, length: u32) {
        self.submit(seqnum, Direction::In, 1, length, [0; 8], &[]);
    }

    pub fn bulk_out(&mut self, seqnum: u32, data: &[u8]) {
        self.submit(seqnum, Direction::Out, 2, data.len() as u32, [0; 8], data);
    }

    pub fn unlink(&mut self, seqnum: u32, target: u32) {
        let basic = BasicHeader {
            seqnum,
            devid: DEVID,
            direction: Direction::Out,
            endpoint: 0,
        };
        let message = UrbMessage::CmdUnlink(CmdUnlink {
            basic,
            unlink_seqnum: target,
        });
        self.stream.write_all(&message.encode(&[])).unwrap();
    }

    pub fn read_reply(&mut self) -> Reply {
        let mut header = [0; URB_HEADER_LEN];
        self.stream.read_exact(&mut header).unwrap();
        match UrbMessage::decode_header(&header).unwrap() {
            UrbMessage::RetSubmit(ret) => {
                let direction = self
                    .directions
                    .remove(&ret.basic.seqnum)
                    .expect("RET_SUBMIT for an unknown seqnum");
                let mut data = vec![0; ret.payload_len(direction)];
                self.stream.read_exact(&mut data).unwrap();
                Reply::Submit(ret, data)
            }
            UrbMessage::RetUnlink(ret) => Reply::Unlink(ret),
            other => panic!("server sent a command: {other:?}"),
        }
    }

    /// Reads a RET_SUBMIT, checking its seqnum; returns status and data.
    pub fn expect_submit(&mut self, seqnum: u32) -> (i32, Vec<u8>) {
        match self.read_reply() {
            Reply::Submit(ret, data) => {
                assert_eq!(ret.basic.seqnum, seqnum, "RET_SUBMIT out of order");
                (ret.status, data)
            }
            other => panic!("expected RET_SUBMIT {seqnum}, got {other:?}"),
        }
    }

    /// Reads a RET_UNLINK for unlink `seqnum` and returns its status.
    pub fn expect_unlink(&mut self, seqnum: u32) -> i32 {
        match self.read_reply() {
            Reply::Unlink(ret) => {
                assert_eq!(ret.basic.seqnum, seqnum);
                ret.status
            }
            other => panic!("expected RET_UNLINK {seqnum}, got {other:?}"),
        }
    }

    /// Whether the server closed the connection: a read ends with EOF or a reset, not a timeout.
    pub fn is_closed(&mut self) -> bool {
        let mut byte = [0; 1];
        match self.stream.read(&mut byte) {
            Ok(0) => true,
            Ok(_) => false,
            Err(error) => !matches!(error.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut),
        }
    }
}

pub fn get_descriptor(kind: u8, index: u8, length: u16) -> SetupPacket {
    SetupPacket {
        request_type: 0x80,
        request: 6,
        value: u16::from(kind) << 8 | u16::from(index),
        index: 0,
        length,
    }
}

/// Polls `condition` until it holds; panics after `GUARD`.
pub fn wait_until(what: &str, mut condition: impl FnMut() -> bool) {
    let deadline = std::time::Instant::now() + GUARD;
    while !condition() {
        assert!(
            std::time::Instant::now() < deadline,
            "timed out waiting for {what}"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
}

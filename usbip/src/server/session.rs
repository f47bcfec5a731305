//! One imported connection: the URB stream. The reader answers control and bulk-out requests in order and
//! queues bulk-in requests; a pump thread completes queued ones whenever the device wakes it.

use std::io::{self, ErrorKind, Read};
use std::net::{Shutdown, TcpStream};
use std::sync::{Arc, Mutex};
use std::thread;

use super::device::{BulkIn, UrbError, UsbDevice, errno};
use super::pending::{PendingIn, PendingQueues};
use super::shared::Shared;
use super::standard::ControlState;
use super::sync::lock;
use super::writer::ReplyWriter;
use crate::protocol::{
    BasicHeader, CmdSubmit, CmdUnlink, Direction, RetSubmit, RetUnlink, SetupPacket,
    URB_HEADER_LEN, UrbMessage, iso_packet_count,
};

#[derive(Default)]
struct SessionState {
    pending: PendingQueues,
    control: ControlState,
    closed: bool,
}

struct Session<D> {
    shared: Arc<Shared<D>>,
    state: Mutex<SessionState>,
    writer: ReplyWriter,
}

fn invalid_data(error: impl Into<Box<dyn std::error::Error + Send + Sync>>) -> io::Error {
    io::Error::new(ErrorKind::InvalidData, error)
}

/// Serves the URB stream on `stream` until the host closes it, it is disconnected, or the host breaks
/// the protocol. Queued requests are dropped at the end and the device is told it was detached.
pub(crate) fn run<D: UsbDevice>(shared: Arc<Shared<D>>, stream: TcpStream) -> io::Result<()> {
    let session = Arc::new(Session {
        writer: ReplyWriter::new(stream.try_clone()?),
        shared,
        state: Mutex::new(SessionState::default()),
    });
    let pump = {
        let session = Arc::clone(&session);
        thread::spawn(move || session.pump())
    };
    let result = session.read_loop(&stream);
    let _ = stream.shutdown(Shutdown::Both);
    lock(&session.state).closed = true;
    session.shared.waker.wake();
    let _ = pump.join();
    lock(&session.shared.device).detached();
    session.shared.counters.set_pending(0);
    result
}

impl<D: UsbDevice> Session<D> {
    fn read_loop(&self, mut stream: &TcpStream) -> io::Result<()> {
        loop {
            let mut header = [0; URB_HEADER_LEN];
            match stream.read_exact(&mut header) {
                Ok(()) => {}
                Err(error) if error.kind() == ErrorKind::UnexpectedEof => return Ok(()),
                Err(error) => return Err(error),
            }
            match UrbMessage::decode_header(&header).map_err(invalid_data)? {
                UrbMessage::CmdSubmit(command) => {
                    let mut payload = vec![0; command.payload_len()];
                    stream.read_exact(&mut payload)?;
                    self.submit(&command, &payload)?;
                }
                UrbMessage::CmdUnlink(command) => self.unlink(&command)?,
                UrbMessage::RetSubmit(_) | UrbMessage::RetUnlink(_) => {
                    return Err(invalid_data("the host sent a return message"));
                }
            }
        }
    }

    fn submit(&self, command: &CmdSubmit, payload: &[u8]) -> io::Result<()> {
        let counters = &self.shared.counters;
        counters.submitted();
        let seqnum = command.basic.seqnum;
        let direction = command.basic.direction;
        let data_len = match direction {
            Direction::Out => command.transfer_buffer_length as usize,
            Direction::In => 0,
        };
        let data = payload.get(..data_len).unwrap_or_default();
        counters.received(data.len());
        let endpoint = u8::try_from(command.basic.endpoint).unwrap_or(u8::MAX);
        if iso_packet_count(command.number_of_packets) > 0 || endpoint > 15 {
            return self.reply(seqnum, Err(UrbError::Stall));
        }
        if endpoint == 0 {
            return self.control(command, data);
        }
        let address = match direction {
            Direction::In => endpoint | 0x80,
            Direction::Out => endpoint,
        };
        if !self.shared.descriptors.has_endpoint(address) {
            return self.reply(seqnum, Err(UrbError::Stall));
        }
        match direction {
            Direction::In => self.queue_in(
                address,
                PendingIn {
                    seqnum,
                    max_len: command.transfer_buffer_length as usize,
                },
            ),
            Direction::Out => {
                let result = self.bulk_out(address, data);
                self.reply(seqnum, result.map(|()| Reply::Out(data.len())))
            }
        }
    }

    fn control(&self, command: &CmdSubmit, data: &[u8]) -> io::Result<()> {
        let setup = SetupPacket::from_bytes(command.setup);
        let result = {
            let mut state = lock(&self.state);
            let mut device = lock(&self.shared.device);
            match state
                .control
                .answer(setup, &self.shared.descriptors, &mut *device)
            {
                Some(answer) => answer,
                None => device.control(setup, data),
            }
        };
        let reply = match command.basic.direction {
            Direction::In => result.map(|mut bytes| {
                bytes.truncate(
                    usize::from(setup.length).min(command.transfer_buffer_length as usize),
                );
                Reply::In(bytes)
            }),
            Direction::Out => result.map(|_| Reply::Out(data.len())),
        };
        self.reply(command.basic.seqnum, reply)?;
        // A cleared halt or a new configuration may let queued bulk-in requests go on.
        self.shared.waker.wake();
        Ok(())
    }

    fn bulk_out(&self, address: u8, data: &[u8]) -> Result<(), UrbError> {
        let mut state = lock(&self.state);
        if state.control.is_halted(address) {
            return Err(UrbError::Stall);
        }
        let result = lock(&self.shared.device).bulk_out(address, data);
        if result == Err(UrbError::Stall) {
            state.control.halt(address);
        }
        result
    }

    fn queue_in(&self, address: u8, request: PendingIn) -> io::Result<()> {
        let mut state = lock(&self.state);
        state.pending.push(address, request);
        self.service(&mut state, address)
    }

    /// Completes queued requests of `endpoint`, oldest first, while the device has data for them.
    fn service(&self, state: &mut SessionState, endpoint: u8) -> io::Result<()> {
        while let Some(request) = state.pending.front(endpoint) {
            if state.control.is_halted(endpoint) {
                break;
            }
            let answer = lock(&self.shared.device).bulk_in(endpoint, request.max_len);
            let reply = match answer {
                BulkIn::Pending => break,
                BulkIn::Data(data) if data.len() > request.max_len => {
                    Err(UrbError::Errno(errno::EOVERFLOW))
                }
                BulkIn::Data(data) => Ok(Reply::In(data)),
                BulkIn::Failed(error) => {
                    if error == UrbError::Stall {
                        state.control.halt(endpoint);
                    }
                    Err(error)
                }
            };
            state.pending.pop_front(endpoint);
            self.shared.counters.set_pending(state.pending.len());
            self.reply(request.seqnum, reply)?;
        }
        self.shared.counters.set_pending(state.pending.len());
        Ok(())
    }

    /// Waits for wakes and completes whatever queued requests the device now has data for.
    fn pump(&self) {
        loop {
            self.shared.waker.wait();
            let mut state = lock(&self.state);
            if state.closed {
                return;
            }
            for endpoint in state.pending.endpoints() {
                if self.service(&mut state, endpoint).is_err() {
                    return;
                }
            }
        }
    }

    /// Cancels a queued request (`-ECONNRESET`, and it never gets a `RET_SUBMIT`), or reports that it had
    /// already completed (0). The state lock is held while replying, so no completion can overtake.
    fn unlink(&self, command: &CmdUnlink) -> io::Result<()> {
        let mut state = lock(&self.state);
        let status = if state.pending.remove(command.unlink_seqnum) {
            self.shared.counters.unlinked();
            -errno::ECONNRESET
        } else {
            0
        };
        self.shared.counters.set_pending(state.pending.len());
        let basic = BasicHeader {
            seqnum: command.basic.seqnum,
            ..BasicHeader::default()
        };
        self.writer
            .send(&UrbMessage::RetUnlink(RetUnlink { basic, status }), &[])
    }

    fn reply(&self, seqnum: u32, result: Result<Reply, UrbError>) -> io::Result<()> {
        let (status, actual_length, data) = match result {
            Ok(Reply::In(data)) => (0, data.len(), data),
            Ok(Reply::Out(accepted)) => (0, accepted, Vec::new()),
            Err(error) => (error.status(), 0, Vec::new()),
        };
        let message = RetSubmit {
            basic: BasicHeader {
                seqnum,
                ..BasicHeader::default()
            },
            status,
            actual_length: actual_length as u32,
            ..RetSubmit::default()
        };
        self.shared.counters.completed(data.len());
        self.writer.send(&UrbMessage::RetSubmit(message), &data)
    }
}

/// A successful transfer: the data sent to the host, or how many bytes the device took.
enum Reply {
    In(Vec<u8>),
    Out(usize),
}

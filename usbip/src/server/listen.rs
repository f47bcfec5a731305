//! The accept loop and the operation phase of a connection: device list, import, then the session.

use std::io::{self, ErrorKind, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::num::NonZeroU32;
use std::sync::Arc;
use std::sync::atomic::Ordering;
use std::thread;
use std::time::Duration;

use super::device::UsbDevice;
use super::session;
use super::shared::Shared;
use super::sync::lock;
use crate::protocol::{BusId, DecodeError, OP_HEADER_LEN, OpKind, OpReply, OpRequest};

/// Longest operation request accepted: an import, header and bus id.
const MAX_REQUEST_LEN: usize = OP_HEADER_LEN + 32;
/// Pause after a failed accept (e.g. out of file descriptors) before trying again.
const ACCEPT_RETRY: Duration = Duration::from_millis(50);
/// Import status of a refused import (unknown bus id, or the device is already attached).
const STATUS_REFUSED: NonZeroU32 = NonZeroU32::MIN;

/// Accepts connections until the server stops, each on its own thread.
pub(crate) fn accept_loop<D: UsbDevice>(listener: TcpListener, shared: Arc<Shared<D>>) {
    for stream in listener.incoming() {
        if shared.stopping.load(Ordering::SeqCst) {
            return;
        }
        let Ok(stream) = stream else {
            thread::sleep(ACCEPT_RETRY);
            continue;
        };
        let shared = Arc::clone(&shared);
        thread::spawn(move || {
            let _ = serve_connection(&shared, stream);
        });
    }
}

fn serve_connection<D: UsbDevice>(
    shared: &Arc<Shared<D>>,
    mut stream: TcpStream,
) -> io::Result<()> {
    stream.set_nodelay(true)?;
    match read_request(&mut stream)? {
        OpRequest::DevList => stream.write_all(&OpReply::DevList(vec![shared.exported()]).encode()),
        OpRequest::Import(busid) => import(shared, stream, &busid),
    }
}

/// Reads one operation request, as many bytes as its header says it needs.
fn read_request(stream: &mut TcpStream) -> io::Result<OpRequest> {
    let mut bytes = vec![0; OP_HEADER_LEN];
    stream.read_exact(&mut bytes)?;
    loop {
        match OpRequest::decode(&bytes) {
            Ok((request, _)) => return Ok(request),
            Err(DecodeError::Truncated { needed, .. }) if needed <= MAX_REQUEST_LEN => {
                let have = bytes.len();
                bytes.resize(needed, 0);
                stream.read_exact(&mut bytes[have..])?;
            }
            Err(error) => return Err(io::Error::new(ErrorKind::InvalidData, error)),
        }
    }
}

/// Attaches the device to this connection if the bus id is ours and no session holds it, then serves
/// the URB stream until it ends.
fn import<D: UsbDevice>(
    shared: &Arc<Shared<D>>,
    mut stream: TcpStream,
    busid: &BusId,
) -> io::Result<()> {
    let refused = OpReply::Refused {
        kind: OpKind::Import,
        status: STATUS_REFUSED,
    };
    if *busid != shared.config.busid {
        return stream.write_all(&refused.encode());
    }
    {
        let mut session = lock(&shared.session);
        if session.is_some() {
            drop(session);
            return stream.write_all(&refused.encode());
        }
        *session = Some(stream.try_clone()?);
    }
    let result = stream
        .write_all(&OpReply::Imported(shared.record()).encode())
        .and_then(|()| session::run(Arc::clone(shared), stream));
    *lock(&shared.session) = None;
    result
}

//! The one path to the socket: every reply is written whole under one lock, so headers and data of
//! different replies never interleave.

use std::io::{self, Write};
use std::net::{Shutdown, TcpStream};
use std::sync::Mutex;

use super::sync::lock;
use crate::protocol::UrbMessage;

/// Serialises replies onto the session's socket.
pub(crate) struct ReplyWriter {
    stream: Mutex<TcpStream>,
}

impl ReplyWriter {
    pub(crate) fn new(stream: TcpStream) -> Self {
        Self {
            stream: Mutex::new(stream),
        }
    }

    /// Writes the header and payload as one piece. On failure the socket is shut down, so the session's
    /// reader ends too.
    pub(crate) fn send(&self, message: &UrbMessage, payload: &[u8]) -> io::Result<()> {
        let bytes = message.encode(payload);
        let mut stream = lock(&self.stream);
        stream.write_all(&bytes).inspect_err(|_| {
            let _ = stream.shutdown(Shutdown::Both);
        })
    }
}

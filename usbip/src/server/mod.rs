//! Serves one emulated device over USB/IP on a `TcpListener`, with blocking threads: an accept loop, a
//! thread per connection, and per attached session a reader and a pump that completes queued bulk-in
//! requests when the device wakes it.
//!
//! Start with `spawn(listener, device, ServerConfig::new(busid))`; hand `ServerHandle::waker()` to whatever
//! produces the device's bulk-in data, or change the device through `ServerHandle::with_device`, which
//! wakes the server afterwards.

mod config;
mod counters;
mod device;
mod listen;
mod pending;
mod session;
mod shared;
mod standard;
mod sync;
mod waker;
mod writer;

pub use config::ServerConfig;
pub use counters::CounterSnapshot;
pub use device::{BulkIn, UrbError, UsbDevice, errno};
pub use waker::Waker;

use std::io;
use std::net::{IpAddr, Ipv4Addr, Ipv6Addr, SocketAddr, TcpListener, TcpStream};
use std::sync::Arc;
use std::sync::atomic::Ordering;
use std::thread::{self, JoinHandle};

use shared::Shared;
use sync::lock;

/// A running server. Dropping it stops the server like `stop`.
pub struct ServerHandle<D: UsbDevice> {
    shared: Arc<Shared<D>>,
    local_addr: SocketAddr,
    accept: Option<JoinHandle<()>>,
}

/// Starts serving `device` on `listener` under `config`'s bus id; returns at once.
pub fn spawn<D: UsbDevice>(
    listener: TcpListener,
    device: D,
    config: ServerConfig,
) -> io::Result<ServerHandle<D>> {
    let local_addr = listener.local_addr()?;
    let shared = Arc::new(Shared::new(device, config));
    let accept = {
        let shared = Arc::clone(&shared);
        thread::Builder::new()
            .name("usbip-accept".into())
            .spawn(move || listen::accept_loop(listener, shared))?
    };
    Ok(ServerHandle {
        shared,
        local_addr,
        accept: Some(accept),
    })
}

impl<D: UsbDevice> ServerHandle<D> {
    /// The address the server listens on.
    pub fn local_addr(&self) -> SocketAddr {
        self.local_addr
    }

    /// A handle that tells the server the device may have bulk-in data.
    pub fn waker(&self) -> Waker {
        self.shared.waker.clone()
    }

    /// The traffic counters now.
    pub fn counters(&self) -> CounterSnapshot {
        self.shared.counters.snapshot()
    }

    /// Whether a host has the device imported (until its session has fully ended).
    pub fn is_attached(&self) -> bool {
        lock(&self.shared.session).is_some()
    }

    /// Closes the attached session's socket, which the host sees as an unplug; false when none is attached.
    pub fn disconnect(&self) -> bool {
        self.shared.disconnect()
    }

    /// Runs `f` on the device (between requests), then wakes the server so queued bulk-in requests see any
    /// data `f` produced.
    pub fn with_device<R>(&self, f: impl FnOnce(&mut D) -> R) -> R {
        let result = f(&mut lock(&self.shared.device));
        self.shared.waker.wake();
        result
    }

    /// Stops accepting connections, disconnects the attached host and waits for the accept loop to end.
    pub fn stop(mut self) {
        self.shutdown();
    }

    fn shutdown(&mut self) {
        self.shared.stopping.store(true, Ordering::SeqCst);
        self.shared.disconnect();
        let Some(accept) = self.accept.take() else {
            return;
        };
        // The accept loop sees the flag on its next connection; make one.
        let ip = match self.local_addr.ip() {
            IpAddr::V4(ip) if ip.is_unspecified() => IpAddr::V4(Ipv4Addr::LOCALHOST),
            IpAddr::V6(ip) if ip.is_unspecified() => IpAddr::V6(Ipv6Addr::LOCALHOST),
            ip => ip,
        };
        if TcpStream::connect(SocketAddr::new(ip, self.local_addr.port())).is_ok() {
            let _ = accept.join();
        }
    }
}

impl<D: UsbDevice> Drop for ServerHandle<D> {
    fn drop(&mut self) {
        self.shutdown();
    }
}

//! SocketCAN sink (Linux): `publish()` encodes and enqueues into a bounded queue (drop-oldest, never blocks); an
//! async writer task on tokio writes the frames, counts and reports write errors and bus-off, and reopens the
//! socket with exponential backoff.

use super::CanError;
use super::layout::{CanFrame, EncodedPose, PoseEncoder, PoseFields};
use crate::publish::{PoseSink, PublishError, SinkCounters, TickPoses};
use std::collections::VecDeque;
use std::future::Future;
use std::io;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;
use tokio::sync::Notify;

/// First reopen delay after a failure; doubles up to [`MAX_BACKOFF`].
pub const MIN_BACKOFF: Duration = Duration::from_millis(50);
/// Longest reopen delay.
pub const MAX_BACKOFF: Duration = Duration::from_secs(2);
/// A frame write that takes longer than this counts as failed (bus-off or a saturated bus blocks the socket).
pub const WRITE_TIMEOUT: Duration = Duration::from_millis(50);

/// Something frames can be written to (a CAN socket, or a fake in tests).
pub trait FrameTransport: Send + 'static {
    /// Writes one frame.
    fn write(&mut self, frame: &CanFrame) -> impl Future<Output = io::Result<()>> + Send;
}

/// Opens (and reopens after failures) a [`FrameTransport`].
pub trait TransportOpener: Send + 'static {
    /// The transport it opens.
    type Transport: FrameTransport;
    /// Opens the transport; called from the writer task (inside the tokio runtime).
    fn open(&mut self) -> io::Result<Self::Transport>;
}

/// A raw SocketCAN socket, classic or FD.
pub enum SocketTransport {
    /// Classic CAN socket.
    Classic(socketcan::tokio::CanSocket),
    /// CAN FD socket (also sends classic frames).
    Fd(socketcan::tokio::CanFdSocket),
}

fn to_socketcan(frame: &CanFrame) -> io::Result<socketcan::CanAnyFrame> {
    use socketcan::{EmbeddedFrame, ExtendedId, Id, StandardId};
    let bad = || io::Error::new(io::ErrorKind::InvalidInput, "frame cannot be represented");
    let id: Id = if frame.extended {
        ExtendedId::new(frame.id).ok_or_else(bad)?.into()
    } else {
        StandardId::new(frame.id as u16).ok_or_else(bad)?.into()
    };
    if frame.fd {
        let mut flags = socketcan::frame::FdFlags::empty();
        if frame.fd_flags & 1 != 0 {
            flags |= socketcan::frame::FdFlags::BRS;
        }
        Ok(socketcan::CanFdFrame::with_flags(id, frame.data(), flags)
            .ok_or_else(bad)?
            .into())
    } else {
        Ok(socketcan::CanFrame::new(id, frame.data())
            .ok_or_else(bad)?
            .into())
    }
}

impl FrameTransport for SocketTransport {
    async fn write(&mut self, frame: &CanFrame) -> io::Result<()> {
        match (self, to_socketcan(frame)?) {
            (Self::Classic(s), socketcan::CanAnyFrame::Normal(f)) => {
                s.write_frame(socketcan::CanFrame::Data(f)).await
            }
            (Self::Classic(_), _) => Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                "FD frame on a classic CAN socket",
            )),
            (Self::Fd(s), socketcan::CanAnyFrame::Normal(f)) => s.write_frame(&f).await,
            (Self::Fd(s), socketcan::CanAnyFrame::Fd(f)) => s.write_frame(&f).await,
            (Self::Fd(_), _) => Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                "unsupported frame type",
            )),
        }
    }
}

/// Opens a SocketCAN socket on a named interface.
#[derive(Debug, Clone)]
pub struct SocketOpener {
    /// Interface name, e.g. `can0` or `vcan0`.
    pub iface: String,
    /// Open an FD socket.
    pub fd: bool,
}

impl TransportOpener for SocketOpener {
    type Transport = SocketTransport;

    fn open(&mut self) -> io::Result<SocketTransport> {
        if self.fd {
            let s = socketcan::tokio::CanFdSocket::open(&self.iface)?;
            Ok(SocketTransport::Fd(s))
        } else {
            Ok(SocketTransport::Classic(socketcan::tokio::CanSocket::open(
                &self.iface,
            )?))
        }
    }
}

/// Health of the SocketCAN writer, for the status topic and the exit report.
#[derive(Debug, Clone, Default, PartialEq, Eq, serde::Serialize)]
pub struct SocketHealth {
    /// Frame writes that failed (error or timeout).
    pub write_errors: u64,
    /// Of those, failures that look like bus-off or the link going down (`ENETDOWN`, `ENODEV`, timeouts).
    pub bus_off: u64,
    /// Times the socket was (re)opened successfully after the first open.
    pub reopens: u64,
    /// Whether the writer currently has an open socket.
    pub connected: bool,
    /// The last error, if any.
    pub last_error: Option<String>,
}

struct Shared {
    queue: Mutex<VecDeque<EncodedPose>>,
    capacity: usize,
    notify: Notify,
    closed: AtomicBool,
    published: AtomicU64,
    failed: AtomicU64,
    dropped: AtomicU64,
    health: Mutex<SocketHealth>,
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// A [`PoseSink`] writing to a SocketCAN interface through a bounded queue and an async writer task.
pub struct SocketCanSink {
    name: String,
    encoder: PoseEncoder,
    shared: Arc<Shared>,
    scratch: EncodedPose,
    encode_failed: u64,
}

fn interface_exists(iface: &str) -> bool {
    std::path::Path::new("/sys/class/net").join(iface).exists()
}

fn is_bus_off(e: &io::Error) -> bool {
    const ENETDOWN: i32 = 100;
    const ENODEV: i32 = 19;
    const ENXIO: i32 = 6;
    e.kind() == io::ErrorKind::TimedOut
        || matches!(e.raw_os_error(), Some(ENETDOWN | ENODEV | ENXIO))
}

impl SocketCanSink {
    /// Opens `iface` (classic or FD per `encoder.fd`) and spawns the writer on `runtime`, which must have IO and
    /// time enabled (`enable_all`).
    ///
    /// Fails with [`CanError::NoSuchInterface`] when the interface does not exist and [`CanError::NoCanSupport`]
    /// when the kernel has no CAN sockets; the caller reports it and carries on with its other sinks.
    pub fn open(
        iface: &str,
        encoder: PoseEncoder,
        queue_len: usize,
        runtime: &tokio::runtime::Handle,
    ) -> Result<Self, CanError> {
        if !interface_exists(iface) {
            return Err(CanError::NoSuchInterface {
                iface: iface.to_string(),
            });
        }
        let mut opener = SocketOpener {
            iface: iface.to_string(),
            fd: encoder.fd,
        };
        let transport = {
            let _guard = runtime.enter();
            opener.open().map_err(|source| {
                const EAFNOSUPPORT: i32 = 97;
                // The interface exists (checked above): ENODEV here means it is not a CAN device.
                match source.raw_os_error() {
                    Some(EAFNOSUPPORT) => CanError::NoCanSupport {
                        iface: iface.to_string(),
                        source,
                    },
                    _ => CanError::Open {
                        iface: iface.to_string(),
                        source,
                    },
                }
            })?
        };
        Ok(Self::with_transport(
            format!("can:{iface}"),
            encoder,
            queue_len,
            opener,
            Some(transport),
            runtime,
        ))
    }

    /// A sink over any transport: `initial` is used first, `opener` reopens after failures (tests use a fake).
    pub fn with_transport<O: TransportOpener>(
        name: String,
        encoder: PoseEncoder,
        queue_len: usize,
        opener: O,
        initial: Option<O::Transport>,
        runtime: &tokio::runtime::Handle,
    ) -> Self {
        let capacity = queue_len.max(1);
        let shared = Arc::new(Shared {
            queue: Mutex::new(VecDeque::with_capacity(capacity)),
            capacity,
            notify: Notify::new(),
            closed: AtomicBool::new(false),
            published: AtomicU64::new(0),
            failed: AtomicU64::new(0),
            dropped: AtomicU64::new(0),
            health: Mutex::new(SocketHealth {
                connected: initial.is_some(),
                ..SocketHealth::default()
            }),
        });
        runtime.spawn(writer(name.clone(), Arc::clone(&shared), opener, initial));
        Self {
            name,
            encoder,
            shared,
            scratch: EncodedPose::default(),
            encode_failed: 0,
        }
    }

    /// Writer health (errors, bus-off, reopens, last error).
    pub fn health(&self) -> SocketHealth {
        lock(&self.shared.health).clone()
    }

    /// Poses waiting in the queue.
    pub fn queued(&self) -> usize {
        lock(&self.shared.queue).len()
    }
}

impl PoseSink for SocketCanSink {
    fn name(&self) -> &str {
        &self.name
    }

    fn publish(&mut self, poses: &TickPoses<'_>) -> Result<(), PublishError> {
        let mut first_error = None;
        for est in poses.estimates {
            let fields = PoseFields::from_estimate(est, poses.tick.index);
            if let Err(e) = self.encoder.encode_into(&fields, &mut self.scratch) {
                self.encode_failed += 1;
                first_error.get_or_insert_with(|| format!("object {}: {e}", est.object));
                continue;
            }
            let mut q = lock(&self.shared.queue);
            if q.len() >= self.shared.capacity {
                q.pop_front();
                self.shared.dropped.fetch_add(1, Ordering::Relaxed);
            }
            q.push_back(self.scratch);
            drop(q);
            self.shared.notify.notify_one();
        }
        PublishError::from_first(&self.name, first_error)
    }

    fn counters(&self) -> SinkCounters {
        SinkCounters {
            published: self.shared.published.load(Ordering::Relaxed),
            failed: self.shared.failed.load(Ordering::Relaxed) + self.encode_failed,
            dropped: self.shared.dropped.load(Ordering::Relaxed),
        }
    }

    /// Waits up to 100 ms for the writer to drain the queue.
    fn flush(&mut self) -> Result<(), PublishError> {
        let deadline = std::time::Instant::now() + Duration::from_millis(100);
        while self.queued() > 0 && std::time::Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(1));
        }
        Ok(())
    }
}

impl Drop for SocketCanSink {
    fn drop(&mut self) {
        self.shared.closed.store(true, Ordering::Release);
        self.shared.notify.notify_one();
    }
}

/// Records a failure; `reopen`: the socket is dropped and will be reopened (not for a full transmit queue).
fn note_error(
    name: &str,
    shared: &Shared,
    message: String,
    bus_off: bool,
    count_write: bool,
    reopen: bool,
) {
    let mut h = lock(&shared.health);
    if count_write {
        h.write_errors += 1;
    }
    if bus_off {
        h.bus_off += 1;
    }
    let first = h.connected || h.last_error.is_none();
    if reopen {
        h.connected = false;
    }
    if first {
        eprintln!(
            "warning: {name}: {message}; poses are counted as failed and the socket is reopened with backoff"
        );
    }
    h.last_error = Some(message);
}

async fn writer<O: TransportOpener>(
    name: String,
    shared: Arc<Shared>,
    mut opener: O,
    initial: Option<O::Transport>,
) {
    let mut transport = initial;
    let mut backoff = MIN_BACKOFF;
    loop {
        let item = loop {
            if let Some(item) = lock(&shared.queue).pop_front() {
                break item;
            }
            if shared.closed.load(Ordering::Acquire) {
                return;
            }
            shared.notify.notified().await;
        };
        if transport.is_none() {
            match opener.open() {
                Ok(t) => {
                    transport = Some(t);
                    let mut h = lock(&shared.health);
                    h.reopens += 1;
                    h.connected = true;
                    eprintln!(
                        "{name}: socket reopened after {} write errors",
                        h.write_errors
                    );
                }
                Err(e) => {
                    shared.failed.fetch_add(1, Ordering::Relaxed);
                    note_error(
                        &name,
                        &shared,
                        format!("reopen failed: {e}"),
                        is_bus_off(&e),
                        false,
                        true,
                    );
                    if shared.closed.load(Ordering::Acquire) {
                        return;
                    }
                    tokio::time::sleep(backoff).await;
                    backoff = (backoff * 2).min(MAX_BACKOFF);
                    continue;
                }
            }
        }
        let Some(t) = transport.as_mut() else {
            continue;
        };
        let mut result = Ok(());
        for frame in item.frames() {
            result = match tokio::time::timeout(WRITE_TIMEOUT, t.write(frame)).await {
                Ok(r) => r,
                Err(_) => Err(io::Error::new(
                    io::ErrorKind::TimedOut,
                    "write timed out (bus-off or bus saturated)",
                )),
            };
            if result.is_err() {
                break;
            }
        }
        match result {
            Ok(()) => {
                shared.published.fetch_add(1, Ordering::Relaxed);
                backoff = MIN_BACKOFF;
            }
            Err(e) => {
                const ENOBUFS: i32 = 105;
                shared.failed.fetch_add(1, Ordering::Relaxed);
                let bus_off = is_bus_off(&e);
                // Anything but a full transmit queue: drop the socket and reopen it.
                let reopen = e.raw_os_error() != Some(ENOBUFS);
                note_error(
                    &name,
                    &shared,
                    format!("write failed: {e}"),
                    bus_off,
                    true,
                    reopen,
                );
                if reopen {
                    transport = None;
                }
                if shared.closed.load(Ordering::Acquire) {
                    return;
                }
                tokio::time::sleep(backoff).await;
                backoff = (backoff * 2).min(MAX_BACKOFF);
            }
        }
    }
}

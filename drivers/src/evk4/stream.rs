//! The EVK4's data endpoint as a stream: many asynchronous bulk-IN transfers kept in flight through libusb
//! (rusb's binding), each completion copied into a bounded [`TransferRing`] and the transfer resubmitted at once.
//! Overload never blocks the USB side: a full ring drops the chunk and counts it. A disconnect (a transfer ending
//! with `NO_DEVICE`, or a long run of I/O errors, which is how some unplugs begin) stops the stream and is
//! reported through [`DataStream::is_disconnected`].

use crate::transfer_ring::{RingCounters, TransferRing};
use libusb1_sys as ffi;
use libusb1_sys::constants as c;
use rusb::UsbContext;
use std::os::raw::{c_int, c_void};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::thread::JoinHandle;

/// Consecutive failed transfers after which the camera is taken as gone.
const ERRORS_BEFORE_DISCONNECT: u64 = 64;

/// Sizes of the data path.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StreamConfig {
    /// Bulk transfers kept in flight.
    pub transfers: usize,
    /// Bytes per transfer.
    pub transfer_bytes: usize,
    /// Ring slots (each one transfer's bytes) between USB and the decoder.
    pub ring_slots: usize,
}

impl Default for StreamConfig {
    fn default() -> Self {
        Self {
            transfers: 32,
            transfer_bytes: 128 * 1024,
            ring_slots: 256,
        }
    }
}

/// What the data path did so far.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct StreamCounters {
    /// Transfers that completed with data.
    pub transfers: u64,
    /// Transfers that failed (I/O error, stall, overflow); each also marks a gap in the stream.
    pub transfer_errors: u64,
    /// The ring's counters (bytes kept, chunks and bytes dropped for want of room).
    pub ring: RingCounters,
}

struct Shared {
    ring: Arc<TransferRing>,
    in_flight: AtomicUsize,
    stopping: AtomicBool,
    disconnected: AtomicBool,
    transfers: AtomicU64,
    errors: AtomicU64,
    errors_in_a_row: AtomicU64,
}

/// A running data stream. Dropping it cancels the transfers and waits for them.
pub struct DataStream {
    shared: Arc<Shared>,
    transfers: Vec<*mut ffi::libusb_transfer>,
    _buffers: Vec<Vec<u8>>,
    events: Option<JoinHandle<()>>,
    _handle: Arc<rusb::DeviceHandle<rusb::Context>>,
}

// The raw transfers are touched only by libusb's event thread (callbacks) and by `Drop` after the event thread
// has seen every transfer finish; the stream itself may move between threads.
unsafe impl Send for DataStream {}

extern "system" fn on_transfer(transfer: *mut ffi::libusb_transfer) {
    // SAFETY: libusb passes back the transfer we filled, whose user_data points at the `Shared` that the
    // `DataStream` keeps alive until every transfer has finished; the buffer holds `length` bytes.
    let (shared, status, data) = unsafe {
        let t = &*transfer;
        let shared = &*(t.user_data as *const Shared);
        let len = usize::try_from(t.actual_length).unwrap_or(0);
        (shared, t.status, std::slice::from_raw_parts(t.buffer, len))
    };
    match status {
        c::LIBUSB_TRANSFER_COMPLETED | c::LIBUSB_TRANSFER_TIMED_OUT => {
            if !data.is_empty() {
                shared.ring.push(data);
                shared.transfers.fetch_add(1, Ordering::Relaxed);
            }
            shared.errors_in_a_row.store(0, Ordering::Relaxed);
        }
        c::LIBUSB_TRANSFER_CANCELLED => {}
        c::LIBUSB_TRANSFER_NO_DEVICE => shared.disconnected.store(true, Ordering::SeqCst),
        _ => {
            shared.errors.fetch_add(1, Ordering::Relaxed);
            shared.ring.mark_gap();
            if shared.errors_in_a_row.fetch_add(1, Ordering::Relaxed) + 1
                >= ERRORS_BEFORE_DISCONNECT
            {
                shared.disconnected.store(true, Ordering::SeqCst);
            }
        }
    }
    let go_on = status != c::LIBUSB_TRANSFER_CANCELLED
        && !shared.stopping.load(Ordering::SeqCst)
        && !shared.disconnected.load(Ordering::SeqCst);
    if go_on {
        // SAFETY: the transfer is ours and idle (its callback is running).
        let rc = unsafe { ffi::libusb_submit_transfer(transfer) };
        if rc == 0 {
            return;
        }
        if rc == ffi::constants::LIBUSB_ERROR_NO_DEVICE {
            shared.disconnected.store(true, Ordering::SeqCst);
        } else {
            shared.errors.fetch_add(1, Ordering::Relaxed);
        }
    }
    shared.in_flight.fetch_sub(1, Ordering::SeqCst);
}

impl DataStream {
    /// Starts `config.transfers` transfers on `endpoint` of `handle`, filling `ring`.
    pub fn start(
        handle: Arc<rusb::DeviceHandle<rusb::Context>>,
        endpoint: u8,
        config: StreamConfig,
        ring: Arc<TransferRing>,
    ) -> Result<Self, rusb::Error> {
        let shared = Arc::new(Shared {
            ring,
            in_flight: AtomicUsize::new(0),
            stopping: AtomicBool::new(false),
            disconnected: AtomicBool::new(false),
            transfers: AtomicU64::new(0),
            errors: AtomicU64::new(0),
            errors_in_a_row: AtomicU64::new(0),
        });
        let length =
            c_int::try_from(config.transfer_bytes).map_err(|_| rusb::Error::InvalidParam)?;
        let mut stream = Self {
            shared,
            transfers: Vec::with_capacity(config.transfers),
            _buffers: Vec::with_capacity(config.transfers),
            events: None,
            _handle: handle.clone(),
        };
        for _ in 0..config.transfers.max(1) {
            // SAFETY: allocates a transfer with no isochronous packets; checked for null below.
            let t = unsafe { ffi::libusb_alloc_transfer(0) };
            if t.is_null() {
                return Err(rusb::Error::NoMem);
            }
            stream.transfers.push(t);
            let mut buffer = vec![0u8; config.transfer_bytes];
            // SAFETY: `t` is a fresh transfer; the buffer and `Shared` outlive it (both are freed in `Drop`
            // after the transfer has finished).
            unsafe {
                let tr = &mut *t;
                tr.dev_handle = handle.as_raw();
                tr.endpoint = endpoint;
                tr.transfer_type = c::LIBUSB_TRANSFER_TYPE_BULK;
                tr.timeout = 0;
                tr.length = length;
                tr.buffer = buffer.as_mut_ptr();
                tr.callback = on_transfer;
                tr.user_data = Arc::as_ptr(&stream.shared) as *mut c_void;
                tr.num_iso_packets = 0;
            }
            stream._buffers.push(buffer);
        }
        let context = handle.context().clone();
        let shared = stream.shared.clone();
        stream.events = Some(
            std::thread::Builder::new()
                .name("evk4-usb".into())
                .spawn(move || run_events(&context, &shared))
                .map_err(|_| rusb::Error::NoMem)?,
        );
        for &t in &stream.transfers {
            stream.shared.in_flight.fetch_add(1, Ordering::SeqCst);
            // SAFETY: a filled, idle transfer.
            let rc = unsafe { ffi::libusb_submit_transfer(t) };
            if rc != 0 {
                stream.shared.in_flight.fetch_sub(1, Ordering::SeqCst);
                return Err(if rc == ffi::constants::LIBUSB_ERROR_NO_DEVICE {
                    rusb::Error::NoDevice
                } else {
                    rusb::Error::Io
                });
            }
        }
        Ok(stream)
    }

    /// Whether the camera went away.
    pub fn is_disconnected(&self) -> bool {
        self.shared.disconnected.load(Ordering::SeqCst)
    }

    /// The counters so far.
    pub fn counters(&self) -> StreamCounters {
        StreamCounters {
            transfers: self.shared.transfers.load(Ordering::Relaxed),
            transfer_errors: self.shared.errors.load(Ordering::Relaxed),
            ring: self.shared.ring.counters(),
        }
    }
}

/// Runs libusb's event handling until every transfer has finished after a stop or a disconnect.
fn run_events(context: &rusb::Context, shared: &Shared) {
    let tv = libc::timeval {
        tv_sec: 0,
        tv_usec: 100_000,
    };
    loop {
        if shared.in_flight.load(Ordering::SeqCst) == 0
            && (shared.stopping.load(Ordering::SeqCst)
                || shared.disconnected.load(Ordering::SeqCst))
        {
            return;
        }
        // SAFETY: the context outlives this call; libusb permits concurrent event handling.
        unsafe {
            ffi::libusb_handle_events_timeout_completed(
                context.as_raw(),
                &tv,
                std::ptr::null_mut(),
            );
        }
    }
}

impl Drop for DataStream {
    fn drop(&mut self) {
        self.shared.stopping.store(true, Ordering::SeqCst);
        for &t in &self.transfers {
            // SAFETY: cancelling a transfer that is idle or already finished is a harmless error.
            unsafe {
                ffi::libusb_cancel_transfer(t);
            }
        }
        if let Some(events) = self.events.take() {
            let _ = events.join();
        }
        if self.shared.in_flight.load(Ordering::SeqCst) == 0 {
            for &t in &self.transfers {
                // SAFETY: every transfer has finished (its callback ran and did not resubmit).
                unsafe { ffi::libusb_free_transfer(t) };
            }
        }
        // Otherwise (the event thread could not be started or died) the transfers and buffers leak rather than
        // be freed under libusb.
        if self.shared.in_flight.load(Ordering::SeqCst) != 0 {
            std::mem::forget(std::mem::take(&mut self._buffers));
        }
    }
}

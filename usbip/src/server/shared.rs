//! What every connection of one server shares: the device, its descriptors, the counters, the waker and
//! the attached session's socket.

use std::net::{Shutdown, TcpStream};
use std::sync::Mutex;
use std::sync::atomic::AtomicBool;

use super::config::ServerConfig;
use super::counters::Counters;
use super::device::UsbDevice;
use super::sync::lock;
use super::waker::Waker;
use crate::descriptors::{CONFIGURATION_VALUE, DeviceDescriptors};
use crate::protocol::{DeviceRecord, ExportedDevice};

/// State shared by the accept loop, the sessions and the handle. Lock order: a session's state, then
/// `device`, then the session's writer; `session` is never held with another lock.
pub(crate) struct Shared<D> {
    pub(crate) device: Mutex<D>,
    pub(crate) descriptors: DeviceDescriptors,
    pub(crate) config: ServerConfig,
    pub(crate) waker: Waker,
    pub(crate) counters: Counters,
    /// The attached session's socket; `Some` from the import until the session has fully ended.
    pub(crate) session: Mutex<Option<TcpStream>>,
    pub(crate) stopping: AtomicBool,
}

impl<D: UsbDevice> Shared<D> {
    pub(crate) fn new(device: D, config: ServerConfig) -> Self {
        Self {
            descriptors: device.descriptors().clone(),
            device: Mutex::new(device),
            config,
            waker: Waker::default(),
            counters: Counters::default(),
            session: Mutex::new(None),
            stopping: AtomicBool::new(false),
        }
    }

    /// The record an import reply and the device list carry.
    pub(crate) fn record(&self) -> DeviceRecord {
        let config = &self.config;
        let (path, busid) = (config.path.clone(), config.busid.clone());
        self.descriptors.record(
            path,
            busid,
            config.busnum,
            config.devnum,
            CONFIGURATION_VALUE,
        )
    }

    pub(crate) fn exported(&self) -> ExportedDevice {
        ExportedDevice {
            record: self.record(),
            interfaces: self.descriptors.interface_classes(),
        }
    }

    /// Shuts the attached session's socket down (the host sees an unplug); false when none is attached.
    pub(crate) fn disconnect(&self) -> bool {
        match lock(&self.session).as_ref() {
            Some(stream) => {
                let _ = stream.shutdown(Shutdown::Both);
                true
            }
            None => false,
        }
    }
}

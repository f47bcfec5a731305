//! The device side of USB/IP: serves one emulated USB device to a Linux host's `vhci-hcd` over TCP.
//!
//! `protocol` encodes and decodes the messages, `descriptors` builds a device's standard descriptors, and
//! `server` answers device-list and import requests and then the URB stream, keeping bulk-in requests
//! pending until the device (a `UsbDevice`) has data.

pub mod descriptors;
pub mod protocol;
pub mod server;

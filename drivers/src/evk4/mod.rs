//! The Prophesee EVK4 (IMX636 sensor) over USB.
//!
//! The pure parts, usable without a USB stack (by the driver and by the hardware-in-the-loop emulator):
//! [`treuzell`] (the control protocol's frames), [`imx636`] (register sequences), [`biases`] (bias offsets and
//! their ranges), [`identity`] (supported VID:PIDs and endpoints). With the `usb` feature, [`camera`] opens a
//! camera through `rusb` and [`stream`] runs the data endpoint into a bounded [`ring`](crate::usb_ring).

pub mod biases;
pub mod identity;
pub mod imx636;
pub mod treuzell;

#[cfg(feature = "usb")]
pub mod camera;
#[cfg(feature = "usb")]
pub mod discovery;
#[cfg(feature = "usb")]
pub mod error;
#[cfg(feature = "usb")]
pub mod session;
#[cfg(feature = "usb")]
pub mod stream;

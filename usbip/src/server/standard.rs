//! The standard (chapter 9) requests on endpoint 0 the server answers itself, and the state they keep.

use super::device::{UrbError, UsbDevice};
use crate::descriptors::{CONFIGURATION_VALUE, DeviceDescriptors};
use crate::protocol::{Recipient, RequestKind, SetupPacket};

const GET_STATUS: u8 = 0;
const CLEAR_FEATURE: u8 = 1;
const SET_FEATURE: u8 = 3;
const SET_ADDRESS: u8 = 5;
const GET_DESCRIPTOR: u8 = 6;
const GET_CONFIGURATION: u8 = 8;
const SET_CONFIGURATION: u8 = 9;
const GET_INTERFACE: u8 = 10;
const SET_INTERFACE: u8 = 11;
const SET_SEL: u8 = 0x30;
const SET_ISOCH_DELAY: u8 = 0x31;
const ENDPOINT_HALT: u16 = 0;

/// What a session's standard requests change: the configuration and the halted bulk endpoints.
#[derive(Debug, Default)]
pub(crate) struct ControlState {
    configuration: u8,
    halted: Vec<u8>,
}

type Answer = Option<Result<Vec<u8>, UrbError>>;

impl ControlState {
    /// Whether bulk endpoint `endpoint` is halted (after a stall or `SET_FEATURE(ENDPOINT_HALT)`).
    pub(crate) fn is_halted(&self, endpoint: u8) -> bool {
        self.halted.contains(&endpoint)
    }

    pub(crate) fn halt(&mut self, endpoint: u8) {
        if !self.is_halted(endpoint) {
            self.halted.push(endpoint);
        }
    }

    /// Answers `setup` if it is a standard request the server handles; `None` hands it to the device.
    pub(crate) fn answer<D: UsbDevice>(
        &mut self,
        setup: SetupPacket,
        descriptors: &DeviceDescriptors,
        device: &mut D,
    ) -> Answer {
        if setup.kind() != RequestKind::Standard {
            return None;
        }
        match setup.recipient() {
            Recipient::Device => Some(self.device_request(setup, descriptors, device)),
            Recipient::Interface => self.interface_request(setup, descriptors),
            Recipient::Endpoint => Some(self.endpoint_request(setup, descriptors, device)),
            Recipient::Other => Some(Err(UrbError::Stall)),
        }
    }

    fn device_request<D: UsbDevice>(
        &mut self,
        setup: SetupPacket,
        descriptors: &DeviceDescriptors,
        device: &mut D,
    ) -> Result<Vec<u8>, UrbError> {
        let [index, kind] = setup.value.to_le_bytes();
        match setup.request {
            GET_STATUS => Ok(vec![u8::from(descriptors.spec().self_powered), 0]),
            CLEAR_FEATURE | SET_FEATURE | SET_ADDRESS | SET_SEL | SET_ISOCH_DELAY => Ok(Vec::new()),
            GET_DESCRIPTOR => match descriptors.lookup(kind, index) {
                Some(bytes) => Ok(bytes[..bytes.len().min(usize::from(setup.length))].to_vec()),
                None => Err(UrbError::Stall),
            },
            GET_CONFIGURATION => Ok(vec![self.configuration]),
            SET_CONFIGURATION => {
                let value = u8::try_from(setup.value).map_err(|_| UrbError::Stall)?;
                if value != 0 && value != CONFIGURATION_VALUE {
                    return Err(UrbError::Stall);
                }
                self.configuration = value;
                self.halted.clear();
                device.configured(value);
                Ok(Vec::new())
            }
            _ => Err(UrbError::Stall),
        }
    }

    fn interface_request(&mut self, setup: SetupPacket, descriptors: &DeviceDescriptors) -> Answer {
        let exists =
            u8::try_from(setup.index).is_ok_and(|number| descriptors.has_interface(number));
        let answer = match setup.request {
            GET_STATUS => Ok(vec![0, 0]),
            CLEAR_FEATURE | SET_FEATURE => Ok(Vec::new()),
            GET_INTERFACE => Ok(vec![0]),
            SET_INTERFACE if setup.value == 0 => Ok(Vec::new()),
            SET_INTERFACE => Err(UrbError::Stall),
            _ => return None,
        };
        Some(if exists { answer } else { Err(UrbError::Stall) })
    }

    fn endpoint_request<D: UsbDevice>(
        &mut self,
        setup: SetupPacket,
        descriptors: &DeviceDescriptors,
        device: &mut D,
    ) -> Result<Vec<u8>, UrbError> {
        let endpoint = u8::try_from(setup.index).map_err(|_| UrbError::Stall)?;
        if endpoint & 0x7f == 0 {
            return match setup.request {
                GET_STATUS => Ok(vec![0, 0]),
                CLEAR_FEATURE | SET_FEATURE => Ok(Vec::new()),
                _ => Err(UrbError::Stall),
            };
        }
        if !descriptors.has_endpoint(endpoint) {
            return Err(UrbError::Stall);
        }
        match (setup.request, setup.value) {
            (GET_STATUS, _) => Ok(vec![u8::from(self.is_halted(endpoint)), 0]),
            (CLEAR_FEATURE, ENDPOINT_HALT) => {
                self.halted.retain(|&halted| halted != endpoint);
                device.clear_halt(endpoint);
                Ok(Vec::new())
            }
            (SET_FEATURE, ENDPOINT_HALT) => {
                self.halt(endpoint);
                Ok(Vec::new())
            }
            _ => Err(UrbError::Stall),
        }
    }
}

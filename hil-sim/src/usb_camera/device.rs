//! The emulated EVK4 as a USB device: its descriptors, the model request on EP0, the Treuzell control
//! endpoints and the data endpoint.

use super::control::{self, CameraIdentity, ControlEffect};
use super::playback::{EventStream, Playback};
use super::sensor::{SensorRegisters, SensorState};
use drivers::evk4::identity::{CONTROL_IN, CONTROL_OUT, DATA_IN, MODEL_EVK4, MODEL_REQUEST};
use std::collections::VecDeque;
use std::sync::Arc;
use std::time::Instant;
use usbip::descriptors::{DeviceDescriptors, DeviceSpec, EndpointSpec, InterfaceSpec, Speed};
use usbip::protocol::SetupPacket;
use usbip::server::{BulkIn, UrbError, UsbDevice};

/// The descriptors of an EVK4 (Prophesee's ids, vendor interface 0 with the three bulk endpoints).
pub fn evk4_spec(speed: Speed, serial: &str) -> DeviceSpec {
    let burst = |e: EndpointSpec| {
        if speed == Speed::Super {
            e.with_max_burst(15)
        } else {
            e
        }
    };
    DeviceSpec::new(speed, 0x04B4, 0x00F5)
        .with_strings("Prophesee", "EVK4", serial)
        .with_interface(InterfaceSpec {
            class: 0xFF,
            subclass: 0x19,
            protocol: 0,
            name: None,
            endpoints: vec![
                burst(EndpointSpec::bulk_in(DATA_IN & 0x0F)),
                EndpointSpec::bulk_out(CONTROL_OUT),
                EndpointSpec::bulk_in(CONTROL_IN & 0x0F),
            ],
        })
}

/// What the emulated camera did, for its statistics.
#[derive(Debug, Clone, Default, PartialEq, Eq, serde::Serialize)]
pub struct CameraStats {
    /// Host sessions (configurations by a host's USB stack) so far.
    pub sessions: u64,
    /// Register writes the sensor refused, with the reason.
    pub refused: Vec<String>,
    /// Event bytes sent on the data endpoint.
    pub bytes_sent: u64,
    /// Trigger words taken out because the trigger input was off.
    pub triggers_removed: u64,
    /// Malformed words injected.
    pub malformed_sent: u64,
    /// Whether the whole recording was sent.
    pub finished: bool,
}

/// The emulated camera.
pub struct Evk4Device {
    descriptors: DeviceDescriptors,
    identity: CameraIdentity,
    sensor: SensorRegisters,
    failing_register: Option<u32>,
    /// Control answers waiting for the host, each with whether it acknowledges the sensor's start.
    answers: VecDeque<(Vec<u8>, bool)>,
    stream: Arc<EventStream>,
    playback: Playback,
    /// When the host read the answer to the write that started the sensor in this session, if it did.
    pub streaming_since: Option<Instant>,
    stats: CameraStats,
}

impl Evk4Device {
    /// A camera that streams `stream` through `playback`.
    pub fn new(
        descriptors: DeviceDescriptors,
        identity: CameraIdentity,
        stream: Arc<EventStream>,
        playback: Playback,
        failing_register: Option<u32>,
    ) -> Self {
        Self {
            descriptors,
            identity,
            sensor: SensorRegisters::with_failing(failing_register),
            failing_register,
            answers: VecDeque::new(),
            stream,
            playback,
            streaming_since: None,
            stats: CameraStats::default(),
        }
    }

    /// The statistics so far.
    pub fn stats(&self) -> CameraStats {
        CameraStats {
            bytes_sent: self.playback.bytes_sent,
            triggers_removed: self.playback.triggers_removed,
            malformed_sent: self.playback.malformed_sent,
            finished: self.playback.finished(&self.stream),
            ..self.stats.clone()
        }
    }

    /// Whether the sensor streams now.
    pub fn streaming(&self) -> bool {
        self.sensor.state() == SensorState::Streaming
    }
}

impl UsbDevice for Evk4Device {
    fn descriptors(&self) -> &DeviceDescriptors {
        &self.descriptors
    }

    fn control(&mut self, setup: SetupPacket, _data_out: &[u8]) -> Result<Vec<u8>, UrbError> {
        if setup.request_type == 0xC0 && setup.request == MODEL_REQUEST {
            return Ok(vec![MODEL_EVK4, 0]);
        }
        Err(UrbError::Stall)
    }

    fn bulk_out(&mut self, endpoint: u8, data: &[u8]) -> Result<(), UrbError> {
        if endpoint != CONTROL_OUT {
            return Err(UrbError::Stall);
        }
        let (answer, effect) = control::answer(data, &self.identity, &mut self.sensor);
        if let ControlEffect::Refused(reason) = effect {
            eprintln!("usb-camera: {reason}");
            self.stats.refused.push(reason);
        }
        if self.streaming() {
            self.playback.start(Instant::now());
        }
        self.answers
            .push_back((answer, self.streaming() && self.streaming_since.is_none()));
        Ok(())
    }

    fn bulk_in(&mut self, endpoint: u8, max_len: usize) -> BulkIn {
        match endpoint {
            CONTROL_IN => match self.answers.pop_front() {
                Some((a, starts)) if a.len() <= max_len => {
                    // The host has the answer to the write that started the sensor: it is streaming now.
                    if starts {
                        self.streaming_since.get_or_insert(Instant::now());
                    }
                    BulkIn::Data(a)
                }
                Some(_) => BulkIn::Failed(UrbError::Errno(usbip::server::errno::EOVERFLOW)),
                None => BulkIn::Pending,
            },
            DATA_IN if self.streaming() => {
                let trigger = self.sensor.trigger_input();
                match self
                    .playback
                    .next(&self.stream, max_len, trigger, Instant::now())
                {
                    Some(bytes) => BulkIn::Data(bytes),
                    None => BulkIn::Pending,
                }
            }
            DATA_IN => BulkIn::Pending,
            _ => BulkIn::Failed(UrbError::Stall),
        }
    }

    fn configured(&mut self, value: u8) {
        if value != 0 {
            self.stats.sessions += 1;
        }
    }

    fn detached(&mut self) {
        // An unplug powers the camera down: the next session starts from reset registers.
        self.sensor = SensorRegisters::with_failing(self.failing_register);
        self.answers.clear();
        self.streaming_since = None;
    }
}

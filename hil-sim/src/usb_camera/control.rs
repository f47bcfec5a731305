//! The emulated camera's side of the Treuzell control protocol: one answer per request, from the identity and
//! the sensor's register file.

use super::sensor::SensorRegisters;
use drivers::evk4::treuzell::{
    self, FAILURE_FLAG, UNKNOWN_COMMAND, WRITE_FLAG, payload_word, property,
};

/// `EIO`: what a failed register access reports.
const EIO: u32 = 5;
/// `EINVAL`: a request whose payload is malformed.
const EINVAL: u32 = 22;

/// Who the emulated camera says it is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CameraIdentity {
    /// Serial number (printed as hex).
    pub serial: u64,
    /// Firmware release (`major << 16 | minor << 8 | patch`).
    pub release: u32,
    /// Firmware build date (seconds since the Unix epoch).
    pub build_date: u32,
}

impl Default for CameraIdentity {
    fn default() -> Self {
        Self {
            serial: 0x00EE_6D00,
            release: 0x0003_0900,
            build_date: 1_700_000_000,
        }
    }
}

const DEVICE_NAME: &str = "CCam5 Imx636 Event-Based Camera";
const DEVICE_COMPATIBLE: &str = "psee,ccam5_imx636";

fn words(values: &[u32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

fn device_string(text: &str) -> Vec<u8> {
    let mut out = 0u32.to_le_bytes().to_vec();
    out.extend_from_slice(text.as_bytes());
    out.push(0);
    out
}

/// What a request did to the sensor, for the emulator's log and its checks.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ControlEffect {
    /// Nothing beyond the answer.
    None,
    /// A register write was refused (the answer is a failure).
    Refused(String),
}

/// Answers one request frame; returns the answer frame and what it did.
pub fn answer(
    request: &[u8],
    id: &CameraIdentity,
    sensor: &mut SensorRegisters,
) -> (Vec<u8>, ControlEffect) {
    let Some((property, _, payload)) = treuzell::split_frame(request) else {
        return (
            treuzell::encode_answer(UNKNOWN_COMMAND, &[]),
            ControlEffect::None,
        );
    };
    let ok = |payload: &[u8]| {
        (
            treuzell::encode_answer(property, payload),
            ControlEffect::None,
        )
    };
    let fail = |errno: u32, effect: ControlEffect| {
        (
            treuzell::encode_answer(property | FAILURE_FLAG, &words(&[0, errno])),
            effect,
        )
    };
    match property {
        property::SERIAL => ok(&id.serial.to_le_bytes()),
        property::RELEASE_VERSION => ok(&id.release.to_le_bytes()),
        property::BUILD_DATE => ok(&id.build_date.to_le_bytes()),
        property::DEVICE_COUNT => ok(&1u32.to_le_bytes()),
        property::DEVICE_NAME => ok(&device_string(DEVICE_NAME)),
        property::DEVICE_COMPATIBLE => ok(&device_string(DEVICE_COMPATIBLE)),
        property::FPGA_STATE => ok(&1u32.to_le_bytes()),
        p if p == property::DEVICE_REGISTER => {
            let (Some(0), Some(address)) = (payload_word(payload, 0), payload_word(payload, 1))
            else {
                return fail(EINVAL, ControlEffect::None);
            };
            let value = sensor.read(address);
            ok(&words(&[0, address, value]))
        }
        p if p == property::DEVICE_REGISTER | WRITE_FLAG => {
            let (Some(0), Some(address), Some(value)) = (
                payload_word(payload, 0),
                payload_word(payload, 1),
                payload_word(payload, 2),
            ) else {
                return fail(EINVAL, ControlEffect::None);
            };
            match sensor.write(address, value) {
                Ok(()) => ok(payload),
                Err(refusal) => fail(EIO, ControlEffect::Refused(refusal.to_string())),
            }
        }
        _ => (
            treuzell::encode_answer(UNKNOWN_COMMAND, &[]),
            ControlEffect::None,
        ),
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use drivers::evk4::treuzell::{Request, TreuzellError};

    fn ask(request: &Request, sensor: &mut SensorRegisters) -> Vec<u8> {
        answer(&request.encode(), &CameraIdentity::default(), sensor).0
    }

    #[test]
    fn the_driver_side_accepts_every_answer() {
        let mut s = SensorRegisters::default();
        let r = Request::read(property::SERIAL);
        assert_eq!(
            r.check_answer(&ask(&r, &mut s)).unwrap(),
            &0x00EE_6D00u64.to_le_bytes()
        );
        let r = Request::register_read(0x0014);
        assert_eq!(
            r.check_register_answer(&ask(&r, &mut s)).unwrap(),
            0xA040_1806
        );
        let r = Request::register_write(0x7004, 0xC5FF);
        r.check_answer(&ask(&r, &mut s)).unwrap();
        assert!(s.trigger_input());
        let r = Request::read_with(property::DEVICE_COMPATIBLE, &[0]);
        assert!(
            r.check_answer(&ask(&r, &mut s))
                .unwrap()
                .ends_with(b"psee,ccam5_imx636\0")
        );
    }

    #[test]
    fn a_refused_write_and_an_unknown_command_come_back_as_the_protocol_says() {
        let mut s = SensorRegisters::default();
        let r = Request::register_write(0x0004, 0xF000_5442);
        let (a, effect) = answer(&r.encode(), &CameraIdentity::default(), &mut s);
        assert!(matches!(effect, ControlEffect::Refused(ref m) if m.contains("0x0004")));
        assert_eq!(
            r.check_answer(&a),
            Err(TreuzellError::Failed {
                property: r.property,
                errno: EIO
            })
        );
        let r = Request::read(0x1234);
        assert_eq!(
            r.check_answer(&ask(&r, &mut s)),
            Err(TreuzellError::UnknownCommand { property: 0x1234 })
        );
    }
}

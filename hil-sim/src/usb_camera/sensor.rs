//! The emulated IMX636's register file and the order the real sensor needs: a reset pulse and the
//! initialisation before anything starts, the output and time base before the analog front end, and the trigger
//! input's enable bit. A write the sensor could not take (a start before initialisation) is refused with the
//! register named, as the camera's firmware answers with a failed command.

use std::collections::HashMap;

/// The register values the initialisation sequence leaves behind, which the sensor needs before it starts
/// (address, value; from the IMX636's ISSD).
const INITIALISED: [(u32, u32); 12] = [
    (0x0000, 0x4F00_644A),
    (0x0018, 0x0000_0200),
    (0x00B8, 0x0000_0409),
    (0x7000, 0x0007_0001),
    (0x8000, 0x0001_E085),
    (0x9000, 0x0000_0200),
    (0xA000, 0x000B_0501),
    (0xA004, 0x000B_0501),
    (0xA008, 0x0000_2405),
    (0xA020, 0x0000_0150),
    (0xB044, 0x0000_0001),
    (0xB0C8, 0x0000_0003),
];

const RESET: u32 = 0x0040_0004;
const ROI_CTRL: u32 = 0x0004;
const ANALOG_CTRL: u32 = 0x002C;
const EDF_CONTROL: u32 = 0x7004;
const TIME_BASE_CTRL: u32 = 0x9008;
const RO_CTRL: u32 = 0x9028;
const MIPI_CTRL: u32 = 0xB000;
const TD_RSTN: u32 = 1 << 10;
const TRIGGER_INPUT: u32 = 1 << 10;

/// The chip identifier register and what an IMX636 reads there.
pub const CHIP_ID: (u32, u32) = (0x0014, 0xA040_1806);

/// Factory bias registers (address, value): the 8-bit code in bits 7..0 over the bias's fixed fields.
const FACTORY_BIASES: [(u32, u32); 8] = [
    (0x1000, 0x11A1_007C),
    (0x1004, 0x11A1_0053),
    (0x100C, 0x11A1_0000),
    (0x1010, 0x11A1_0066),
    (0x1014, 0x11A1_504D),
    (0x1018, 0x11A1_0049),
    (0x101C, 0x11A1_005B),
    (0x1020, 0x11A1_0014),
];

/// A register write the sensor refuses, with the reason.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Refusal {
    /// The register written.
    pub address: u32,
    /// The value written.
    pub value: u32,
    /// Why the sensor cannot take it.
    pub reason: String,
}

impl std::fmt::Display for Refusal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "register {:#06x} = {:#x} refused: {}",
            self.address, self.value, self.reason
        )
    }
}

/// The sensor's state as the data endpoint sees it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SensorState {
    /// Powered, not (fully) initialised.
    Idle,
    /// Initialised, not streaming.
    Ready,
    /// The analog front end runs: events flow.
    Streaming,
}

/// The register file.
#[derive(Debug, Clone)]
pub struct SensorRegisters {
    values: HashMap<u32, u32>,
    reset_pulsed: bool,
    /// Register whose every write fails (a fault mode), if any.
    pub failing: Option<u32>,
    /// Every write the sensor accepted, in order (for tests and the emulator's log).
    pub writes: u64,
}

impl Default for SensorRegisters {
    fn default() -> Self {
        let mut values: HashMap<u32, u32> = FACTORY_BIASES.into_iter().collect();
        values.insert(CHIP_ID.0, CHIP_ID.1);
        Self {
            values,
            reset_pulsed: false,
            failing: None,
            writes: 0,
        }
    }
}

impl SensorRegisters {
    /// A sensor at power-on whose writes to `failing` (if any) fail.
    pub fn with_failing(failing: Option<u32>) -> Self {
        Self {
            failing,
            ..Self::default()
        }
    }

    /// The value of a register (0 when never written and not a factory value).
    pub fn read(&self, address: u32) -> u32 {
        self.values.get(&address).copied().unwrap_or(0)
    }

    /// Whether the initialisation sequence has run since the last reset pulse.
    pub fn initialised(&self) -> bool {
        self.reset_pulsed && INITIALISED.iter().all(|&(a, v)| self.read(a) == v)
    }

    /// The state the data endpoint follows.
    pub fn state(&self) -> SensorState {
        if self.read(ROI_CTRL) & TD_RSTN != 0 && self.initialised() {
            SensorState::Streaming
        } else if self.initialised() {
            SensorState::Ready
        } else {
            SensorState::Idle
        }
    }

    /// Whether the external trigger input (channel 0) is enabled.
    pub fn trigger_input(&self) -> bool {
        self.read(EDF_CONTROL) & TRIGGER_INPUT != 0
    }

    /// Applies a write, or refuses it as the sensor would.
    pub fn write(&mut self, address: u32, value: u32) -> Result<(), Refusal> {
        let refuse = |reason: String| {
            Err(Refusal {
                address,
                value,
                reason,
            })
        };
        if self.failing == Some(address) {
            return refuse(
                "the register does not answer (fault injected with --fail-register)".into(),
            );
        }
        if address == RESET {
            if value == 0 && self.read(RESET) == 1 {
                self.reset_pulsed = true;
                for (a, _) in INITIALISED {
                    self.values.remove(&a);
                }
            }
        } else if address == ROI_CTRL
            && value & TD_RSTN != 0
            && let Some(reason) = self.start_problem()
        {
            return refuse(reason);
        }
        self.values.insert(address, value);
        self.writes += 1;
        Ok(())
    }

    /// What stops the analog front end from starting now, if anything.
    fn start_problem(&self) -> Option<String> {
        if !self.reset_pulsed {
            return Some("analog start before the sensor's reset pulse (0x400004 = 1 then 0) and initialisation".into());
        }
        if let Some(&(a, v)) = INITIALISED.iter().find(|&&(a, v)| self.read(a) != v) {
            return Some(format!(
                "analog start before the initialisation finished: register {a:#06x} reads {:#x}, initialised it is {v:#x}",
                self.read(a)
            ));
        }
        if self.read(MIPI_CTRL) != 0x2F9 {
            return Some(format!(
                "analog start with the readout link off (0xb000 reads {:#x}, start writes 0x2f9)",
                self.read(MIPI_CTRL)
            ));
        }
        if self.read(RO_CTRL) != 0 {
            return Some(format!(
                "analog start with the output disabled (0x9028 reads {:#x}, start writes 0)",
                self.read(RO_CTRL)
            ));
        }
        if self.read(TIME_BASE_CTRL) & 1 == 0 {
            return Some("analog start with the time base stopped (0x9008 bit 0 clear)".into());
        }
        if self.read(ANALOG_CTRL) != 0x0022_C724 {
            return Some(format!(
                "analog start with the analog block off (0x002c reads {:#x}, start writes 0x22c724)",
                self.read(ANALOG_CTRL)
            ));
        }
        None
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use drivers::evk4::imx636::{self, RegisterOp};

    fn run(s: &mut SensorRegisters, ops: &[RegisterOp]) -> Result<(), Refusal> {
        for op in ops {
            if let RegisterOp::Write { address, value } = *op {
                s.write(address, value)?;
            }
        }
        Ok(())
    }

    #[test]
    fn the_issd_sequences_start_and_stop_the_sensor() {
        let mut s = SensorRegisters::default();
        assert_eq!(s.read(CHIP_ID.0), CHIP_ID.1);
        run(&mut s, imx636::INIT).unwrap();
        assert_eq!(s.state(), SensorState::Ready);
        assert!(!s.trigger_input());
        run(&mut s, &[imx636::trigger_input(true)]).unwrap();
        assert!(s.trigger_input());
        run(&mut s, imx636::START).unwrap();
        assert_eq!(s.state(), SensorState::Streaming);
        run(&mut s, imx636::STOP).unwrap();
        assert_eq!(s.state(), SensorState::Ready);
    }

    #[test]
    fn a_start_without_initialisation_is_refused_naming_the_register() {
        let mut s = SensorRegisters::default();
        let e = run(&mut s, imx636::START).unwrap_err();
        assert_eq!(e.address, 0x0004);
        assert!(e.to_string().contains("reset pulse"), "{e}");
        // An initialisation that skipped one write is refused with the missing register.
        let mut s = SensorRegisters::default();
        let partial: Vec<_> = imx636::INIT
            .iter()
            .copied()
            .filter(|op| {
                !matches!(
                    op,
                    RegisterOp::Write {
                        address: 0xA020,
                        ..
                    }
                )
            })
            .collect();
        run(&mut s, &partial).unwrap();
        let e = run(&mut s, imx636::START).unwrap_err();
        assert!(e.reason.contains("0xa020"), "{e}");
    }

    #[test]
    fn a_failing_register_is_refused() {
        let mut s = SensorRegisters::with_failing(Some(0x1014));
        let e = run(&mut s, imx636::INIT).unwrap_err();
        assert_eq!(e.address, 0x1014);
    }
}

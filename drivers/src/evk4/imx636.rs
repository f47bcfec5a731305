//! The IMX636 sensor behind the EVK4: register addresses and the register sequences that bring it up, start and
//! stop it, enable the external trigger input and configure the event-rate controller (facts from Prophesee's
//! OpenEB HAL, `imx636_evk3_issd.h`, and the sensor's register map).

/// One step of a register sequence.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RegisterOp {
    /// Write `value` to the register at `address`.
    Write {
        /// Register address.
        address: u32,
        /// Value written.
        value: u32,
    },
    /// Wait this many microseconds before the next step (the sensor's settling times).
    Delay {
        /// Microseconds.
        us: u32,
    },
}

const fn w(address: u32, value: u32) -> RegisterOp {
    RegisterOp::Write { address, value }
}

const fn d(us: u32) -> RegisterOp {
    RegisterOp::Delay { us }
}

/// Register addresses the driver reads or checks by name.
pub mod reg {
    /// Readout and TD control (`td_rstn` is bit 10: the analog start).
    pub const ROI_CTRL: u32 = 0x0004;
    /// The chip identifier; reads [`super::IMX636_CHIP_ID`] on an IMX636.
    pub const CHIP_ID: u32 = 0x0014;
    /// Analog power control (`0x0022C724` running, `0x0022C324` stopped).
    pub const ANALOG_CTRL: u32 = 0x002C;
    /// First bias register; each bias is one 32-bit register, the current code in bits 7..0.
    pub const BIAS_BASE: u32 = 0x1000;
    /// Event-rate controller: its pipeline control (`0x155400` held, `0x155401` running).
    pub const ERC_PIPELINE: u32 = 0x6000;
    /// ERC: drop-rate control enable (bit 0).
    pub const ERC_IN_DROP_RATE: u32 = 0x6004;
    /// ERC: reference period in microseconds (bits 9..0).
    pub const ERC_REFERENCE_PERIOD: u32 = 0x6008;
    /// ERC: target events per reference period (bits 21..0).
    pub const ERC_TARGET_EVENTS: u32 = 0x600C;
    /// ERC: control (bit 0 enable; bit 1 always set).
    pub const ERC_CONTROL: u32 = 0x6028;
    /// ERC: table selector for the two tables below.
    pub const ERC_TABLE_SELECT: u32 = 0x602C;
    /// ERC: temporal dropping enable (bit 0).
    pub const ERC_T_DROPPING: u32 = 0x6050;
    /// ERC: horizontal dropping enable (bit 0).
    pub const ERC_H_DROPPING: u32 = 0x6060;
    /// ERC: vertical dropping enable (bit 0).
    pub const ERC_V_DROPPING: u32 = 0x6070;
    /// ERC: the temporal drop lookup table (256 words).
    pub const ERC_T_DROP_LUT: u32 = 0x6400;
    /// ERC: the dropping table (230 words).
    pub const ERC_DROP_TABLE: u32 = 0x6800;
    /// Event data formatter control; bit 10 enables the external trigger input (channel 0).
    pub const EDF_CONTROL: u32 = 0x7004;
    /// Readout control (`0x200` once the sensor is initialised).
    pub const READOUT_CTRL: u32 = 0x9000;
    /// Time base control; bit 0 runs the time base.
    pub const TIME_BASE_CTRL: u32 = 0x9008;
    /// Readout output control (0 streaming, 2 output disabled).
    pub const RO_CTRL: u32 = 0x9028;
    /// MIPI/readout link control (`0x2F9` on, `0x2F8` off).
    pub const MIPI_CTRL: u32 = 0xB000;
}

/// What [`reg::CHIP_ID`] reads on an IMX636.
pub const IMX636_CHIP_ID: u32 = 0xA040_1806;
/// The oldest firmware release that runs this sequence (`major << 16 | minor << 8 | patch`): 3.8.0.
pub const MIN_FIRMWARE_RELEASE: u32 = 0x0003_0800;
/// Sensor geometry in pixels (width, height).
pub const GEOMETRY: (u16, u16) = (1280, 720);
/// [`reg::EDF_CONTROL`] with the external trigger input (channel 0) enabled.
pub const EDF_TRIGGER_ON: u32 = 0xC5FF;
/// [`reg::EDF_CONTROL`] with the external trigger input disabled.
pub const EDF_TRIGGER_OFF: u32 = 0xC1FF;
/// The bit of [`reg::ROI_CTRL`] that starts the analog front end.
pub const ROI_CTRL_TD_RSTN: u32 = 1 << 10;

/// The bring-up (initialisation) sequence, about 2.5 s of waits in all.
pub const INIT: &[RegisterOp] = &[
    w(0x001C, 0x0000_0001),
    d(1_000_000),
    w(0x0040_0004, 0x0000_0001),
    d(500_000),
    w(0x0040_0004, 0x0000_0000),
    d(1_000_000),
    w(0xB000, 0x0000_0158),
    d(300),
    w(0xB044, 0x0000_0000),
    w(0xB004, 0x0000_000A),
    w(0xB040, 0x0000_0000),
    w(0xB0C8, 0x0000_0000),
    w(0xB040, 0x0000_0000),
    w(0xB040, 0x0000_0000),
    w(0x0000, 0x4F00_6442),
    w(0x0000, 0x0F00_6442),
    w(0x00B8, 0x0000_0400),
    w(0x00B8, 0x0000_0400),
    w(0xB07C, 0x0000_0000),
    w(0xB074, 0x0000_0002),
    w(0xB078, 0x0000_00A0),
    w(0x00C0, 0x0000_0110),
    w(0x00C0, 0x0000_0210),
    w(0xB120, 0x0000_0001),
    w(0xE120, 0x0000_0000),
    w(0xB068, 0x0000_0004),
    w(0xB07C, 0x0000_0001),
    d(10),
    w(0xB07C, 0x0000_0003),
    d(1000),
    w(0x00B8, 0x0000_0401),
    w(0x00B8, 0x0000_0409),
    w(0x0000, 0x4F00_6442),
    w(0x0000, 0x4F00_644A),
    w(0xB080, 0x0000_0077),
    w(0xB084, 0x0000_000F),
    w(0xB088, 0x0000_0037),
    w(0xB08C, 0x0000_0037),
    w(0xB090, 0x0000_00DF),
    w(0xB094, 0x0000_0057),
    w(0xB098, 0x0000_0037),
    w(0xB09C, 0x0000_0067),
    w(0xB0A0, 0x0000_0037),
    w(0xB0A4, 0x0000_002F),
    w(0xB0AC, 0x0000_0028),
    w(0xB0CC, 0x0000_0001),
    w(0xB000, 0x0000_02F8),
    w(0xB004, 0x0000_008A),
    w(0xB01C, 0x0000_0030),
    w(0xB020, 0x0000_2000),
    w(0xB02C, 0x0000_00FF),
    w(0xB030, 0x0000_3E80),
    w(0xB028, 0x0000_0FA0),
    w(0xA000, 0x000B_0501),
    d(200),
    w(0xA008, 0x0000_2405),
    d(200),
    w(0xA004, 0x000B_0501),
    d(200),
    w(0xA020, 0x0000_0150),
    d(200),
    w(0xB040, 0x0000_0007),
    w(0xB064, 0x0000_0006),
    w(0xB040, 0x0000_000F),
    d(100),
    w(0xB004, 0x0000_008A),
    d(200),
    w(0xB0C8, 0x0000_0003),
    d(200),
    w(0xB044, 0x0000_0001),
    w(0xB000, 0x0000_02F9),
    w(0x7008, 0x0000_0001),
    w(0x7000, 0x0007_0001),
    w(0x8000, 0x0001_E085),
    w(0x9008, 0x0000_0644),
    w(0x0004, 0xF000_5042),
    w(0x0018, 0x0000_0200),
    w(0x1014, 0x11A1_504D),
    w(0x9004, 0x0000_0000),
    d(1000),
    w(0x9000, 0x0000_0200),
];

/// Starts streaming: link on, output on, time base running, analog front end on.
pub const START: &[RegisterOp] = &[
    w(0xB000, 0x0000_02F9),
    w(0x9028, 0x0000_0000),
    w(0x9008, 0x0000_0645),
    w(0x002C, 0x0022_C724),
    w(0x0004, 0xF000_5442),
];

/// Stops streaming (the reverse of [`START`]).
pub const STOP: &[RegisterOp] = &[
    w(0x0004, 0xF000_5042),
    w(0x002C, 0x0022_C324),
    w(0x9028, 0x0000_0002),
    d(1000),
    w(0x9008, 0x0000_0644),
    w(0xB000, 0x0000_02F8),
    d(300),
];

/// The external trigger input (channel 0) on or off.
pub fn trigger_input(enabled: bool) -> RegisterOp {
    w(
        reg::EDF_CONTROL,
        if enabled {
            EDF_TRIGGER_ON
        } else {
            EDF_TRIGGER_OFF
        },
    )
}

/// The reference period of the event-rate controller, microseconds (its register holds 10 bits).
pub const ERC_REFERENCE_PERIOD_US: u32 = 200;
/// The largest target the ERC's register holds, events per reference period (22 bits).
pub const ERC_MAX_EVENTS_PER_PERIOD: u32 = (1 << 22) - 1;

/// The event-rate controller's sequence: with `Some(rate)` it caps the sensor's output near `rate` events per
/// second (dropping uniformly in time), with `None` it passes every event. The caller checks the rate's range
/// ([`erc_events_per_period`]).
pub fn erc(cap: Option<u32>) -> Vec<RegisterOp> {
    let mut ops = vec![w(reg::ERC_PIPELINE, 0x0015_5400)];
    match cap {
        Some(per_period) => {
            ops.extend([
                w(reg::ERC_IN_DROP_RATE, 1),
                w(reg::ERC_REFERENCE_PERIOD, ERC_REFERENCE_PERIOD_US),
                w(reg::ERC_TARGET_EVENTS, per_period),
                w(reg::ERC_CONTROL, 0b11),
                w(reg::ERC_TABLE_SELECT, 1),
            ]);
            ops.extend((0..230).map(|i| w(reg::ERC_DROP_TABLE + 4 * i, 0x0808_0808)));
            ops.push(w(reg::ERC_TABLE_SELECT, 2));
            ops.extend(
                (0..256).map(|i| w(reg::ERC_T_DROP_LUT + 4 * i, ((2 * i + 1) << 16) | (2 * i))),
            );
        }
        None => ops.extend([w(reg::ERC_IN_DROP_RATE, 0), w(reg::ERC_CONTROL, 0b10)]),
    }
    let on = u32::from(cap.is_some());
    ops.extend([
        w(reg::ERC_T_DROPPING, on),
        w(reg::ERC_H_DROPPING, 0),
        w(reg::ERC_V_DROPPING, 0),
        w(reg::ERC_PIPELINE, 0x0015_5401),
    ]);
    ops
}

/// The ERC target for a cap of `events_per_second`, in events per reference period; `None` when the cap is
/// below one event per period or above what the register holds.
pub fn erc_events_per_period(events_per_second: f64) -> Option<u32> {
    let per_period = events_per_second * f64::from(ERC_REFERENCE_PERIOD_US) * 1e-6;
    (per_period.is_finite() && (1.0..=f64::from(ERC_MAX_EVENTS_PER_PERIOD)).contains(&per_period))
        .then(|| per_period.round() as u32)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    fn writes(ops: &[RegisterOp]) -> Vec<(u32, u32)> {
        ops.iter()
            .filter_map(|op| match *op {
                RegisterOp::Write { address, value } => Some((address, value)),
                RegisterOp::Delay { .. } => None,
            })
            .collect()
    }

    #[test]
    fn an_erc_cap_sets_its_target_and_tables_and_no_cap_turns_it_off() {
        // 20 Mev/s over a 200 us reference period: 4000 events per period.
        let target = erc_events_per_period(20e6).unwrap();
        assert_eq!(target, 4000);
        let on = writes(&erc(Some(target)));
        assert!(on.contains(&(reg::ERC_TARGET_EVENTS, 4000)));
        assert!(on.contains(&(reg::ERC_REFERENCE_PERIOD, 200)));
        assert!(on.contains(&(reg::ERC_T_DROPPING, 1)));
        assert_eq!(
            on.iter()
                .filter(|(a, _)| (reg::ERC_T_DROP_LUT..reg::ERC_T_DROP_LUT + 1024).contains(a))
                .count(),
            256
        );
        assert_eq!(on.first(), Some(&(reg::ERC_PIPELINE, 0x0015_5400)));
        assert_eq!(on.last(), Some(&(reg::ERC_PIPELINE, 0x0015_5401)));
        let off = writes(&erc(None));
        assert!(off.contains(&(reg::ERC_CONTROL, 0b10)));
        assert!(off.contains(&(reg::ERC_T_DROPPING, 0)));
        assert!(!off.iter().any(|(a, _)| *a == reg::ERC_TARGET_EVENTS));
    }

    #[test]
    fn erc_caps_outside_the_register_are_refused() {
        assert_eq!(
            erc_events_per_period(1000.0),
            None,
            "below one event per period"
        );
        assert_eq!(erc_events_per_period(f64::NAN), None);
        assert_eq!(
            erc_events_per_period(1e13),
            None,
            "beyond 22 bits per period"
        );
        assert!(erc_events_per_period(5000.0).is_some());
    }

    #[test]
    fn the_trigger_input_is_bit_10_of_the_edf_control() {
        assert_eq!(
            trigger_input(true),
            RegisterOp::Write {
                address: 0x7004,
                value: 0xC5FF
            }
        );
        assert_eq!(
            trigger_input(false),
            RegisterOp::Write {
                address: 0x7004,
                value: 0xC1FF
            }
        );
        assert_eq!(EDF_TRIGGER_ON & !EDF_TRIGGER_OFF, 1 << 10);
    }
}

//! The IMX636's adjustable bias currents, set as offsets from their factory codes within the ranges Prophesee
//! allows (OpenEB `imx636_bias_settings.h`). Each bias is one register; its current code is bits 7..0.

use thiserror::Error;

/// One adjustable bias.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Bias {
    /// The name used in configuration files and recording headers (`bias_fo`, ...).
    pub name: &'static str,
    /// Register address.
    pub address: u32,
    /// The factory code (bits 7..0 of the register after bring-up).
    pub factory: u8,
    /// The smallest allowed offset from the factory code.
    pub min_offset: i16,
    /// The largest allowed offset from the factory code.
    pub max_offset: i16,
}

/// Every adjustable bias, in register order.
pub const BIASES: [Bias; 6] = [
    Bias {
        name: "bias_fo",
        address: 0x1004,
        factory: 0x53,
        min_offset: -35,
        max_offset: 55,
    },
    Bias {
        name: "bias_hpf",
        address: 0x100C,
        factory: 0x00,
        min_offset: 0,
        max_offset: 120,
    },
    Bias {
        name: "bias_diff_on",
        address: 0x1010,
        factory: 0x66,
        min_offset: -85,
        max_offset: 140,
    },
    Bias {
        name: "bias_diff",
        address: 0x1014,
        factory: 0x4D,
        min_offset: -25,
        max_offset: 23,
    },
    Bias {
        name: "bias_diff_off",
        address: 0x1018,
        factory: 0x49,
        min_offset: -35,
        max_offset: 190,
    },
    Bias {
        name: "bias_refr",
        address: 0x1020,
        factory: 0x14,
        min_offset: -20,
        max_offset: 235,
    },
];

/// A bias setting that the sensor does not allow.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum BiasError {
    /// No bias of that name.
    #[error(
        "unknown bias `{name}` (adjustable: bias_fo, bias_hpf, bias_diff_on, bias_diff, bias_diff_off, bias_refr)"
    )]
    Unknown {
        /// The name given.
        name: String,
    },
    /// The offset is outside the bias's range.
    #[error("{name} = {offset} is outside its allowed offsets {min}..={max} from the factory code")]
    OutOfRange {
        /// The bias.
        name: &'static str,
        /// The offset given.
        offset: i64,
        /// Smallest allowed offset.
        min: i16,
        /// Largest allowed offset.
        max: i16,
    },
}

/// Offsets from the factory codes, one per bias; an offset of 0 leaves the bias at its factory code.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct BiasOffsets {
    offsets: [i16; BIASES.len()],
}

impl BiasOffsets {
    /// The offsets named in `settings` (`(name, offset)`), each checked against its range.
    pub fn from_named<'a>(
        settings: impl IntoIterator<Item = (&'a str, i64)>,
    ) -> Result<Self, BiasError> {
        let mut out = Self::default();
        for (name, offset) in settings {
            let i =
                BIASES
                    .iter()
                    .position(|b| b.name == name)
                    .ok_or_else(|| BiasError::Unknown {
                        name: name.to_owned(),
                    })?;
            let b = BIASES[i];
            if offset < i64::from(b.min_offset) || offset > i64::from(b.max_offset) {
                return Err(BiasError::OutOfRange {
                    name: b.name,
                    offset,
                    min: b.min_offset,
                    max: b.max_offset,
                });
            }
            out.offsets[i] = offset as i16;
        }
        Ok(out)
    }

    /// The offset of each bias, in [`BIASES`] order.
    pub fn iter(&self) -> impl Iterator<Item = (Bias, i16)> + '_ {
        BIASES.iter().copied().zip(self.offsets.iter().copied())
    }

    /// The register value that sets `bias` from its current value `current`: the code in bits 7..0 replaced by
    /// the factory code plus the offset, every other field kept.
    pub fn register_value(bias: Bias, offset: i16, current: u32) -> u32 {
        let code = (i16::from(bias.factory) + offset).clamp(0, 255) as u32;
        (current & !0xFF) | code
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn offsets_in_range_are_applied_over_the_factory_code_and_others_are_refused() {
        let o = BiasOffsets::from_named([("bias_diff_on", 20), ("bias_refr", -20)]).unwrap();
        let (diff_on, off) = o.iter().find(|(b, _)| b.name == "bias_diff_on").unwrap();
        assert_eq!(off, 20);
        // The code (bits 7..0) becomes factory + offset; the bias's other fields are kept.
        assert_eq!(
            BiasOffsets::register_value(diff_on, off, 0x11A1_5566),
            0x11A1_557A
        );
        assert_eq!(
            BiasOffsets::from_named([("bias_diff", 24)]),
            Err(BiasError::OutOfRange {
                name: "bias_diff",
                offset: 24,
                min: -25,
                max: 23
            })
        );
        assert!(matches!(
            BiasOffsets::from_named([("bias_pr", 1)]),
            Err(BiasError::Unknown { .. })
        ));
        let e = BiasOffsets::from_named([("bias_hpf", -1)])
            .unwrap_err()
            .to_string();
        assert!(e.contains("bias_hpf") && e.contains("0..=120"), "{e}");
    }
}

//! The EventTrack6D CAN pose layout: pure encoders, decoders, CRC-8 and the classic-frame assembler.
//!
//! See `docs/can.md` and `config/can/eventtrack6d.dbc`. All multi-byte fields are little-endian (Intel byte order).
//!
//! Classic CAN (4 frames of 8 bytes per pose, object `n`, standard 11-bit identifiers):
//!
//! | id                | b0  | b1      | b2..b4      | b5..b7          | b2..b7 (other frames)        |
//! |-------------------|-----|---------|-------------|-----------------|------------------------------|
//! | `base + 4n + 0`   | CRC | counter | x i24       | y i24           |                              |
//! | `base + 4n + 1`   | CRC | counter | z i24       | quality u8, state u8, object u8 |              |
//! | `base + 4n + 2`   | CRC | counter |             |                 | qx i16, qy i16, qz i16       |
//! | `base + 4n + 3`   | CRC | counter |             |                 | qw i16, t_us low 32 bits u32 |
//!
//! CAN FD (one 48-byte frame per pose, id `base + 0x40 + n`): CRC, counter, state, object, quality u16,
//! 2 reserved bytes, t_us i64, tick index u32, x y z i32, qx qy qz qw i32.
//!
//! Position: classic 1e-5 m (0.01 mm) per LSB, range +-83.886 m; FD 1e-6 m, range +-2147 m.
//! Quaternion (x, y, z, w), `w >= 0`: classic 2^-15 per LSB (raw clamped to +-32767); FD 2^-30.
//! Quality: classic 0.004 per LSB (raw 0..=250); FD 0.0001 (raw 0..=10000). State: 0 tracking, 1 degraded, 2 lost.
//! Counter: tick index mod 256, identical in every frame of one pose.
//! CRC: CRC-8/AUTOSAR (polynomial 0x2F, init 0xFF, no reflection, final XOR 0xFF; check value 0xDF for
//! `"123456789"`) over the identifier as two bytes (low byte first) followed by bytes 1.. of the frame.

mod assembler;
mod crc;
mod decode;
mod encode;
mod frame;

pub use assembler::{Assembler, AssemblerCounters};
pub use crc::{CRC8_POLY, crc8_autosar, frame_crc};
pub use decode::{
    ClassicPart, DecodeError, DecodedPose, FrameSlot, classify, decode_classic, decode_fd,
};
pub use encode::{EncodeError, EncodedPose, PoseEncoder, PoseFields, encode_classic, encode_fd};
pub use frame::{CanFrame, FD_LENGTHS};

/// Largest number of objects the layout addresses (classic uses 4 identifiers per object, FD one).
pub const MAX_OBJECTS: usize = 16;
/// Classic frames per pose.
pub const CLASSIC_FRAMES: usize = 4;
/// Offset of the FD identifiers from the base identifier (`base + FD_ID_OFFSET + object`).
pub const FD_ID_OFFSET: u16 = 0x40;
/// Number of identifiers the layout occupies from the base identifier (classic and FD together).
pub const ID_SPAN: u16 = FD_ID_OFFSET + MAX_OBJECTS as u16;
/// Largest allowed base identifier so that every identifier stays an 11-bit standard identifier.
pub const MAX_BASE_ID: u16 = 0x7FF + 1 - ID_SPAN;
/// Default base identifier (0x300).
pub const DEFAULT_BASE_ID: u16 = 0x300;
/// Length of the CAN FD pose frame, bytes (a valid FD length).
pub const FD_LEN: usize = 48;
/// Classic frame length, bytes.
pub const CLASSIC_LEN: usize = 8;

/// Classic position resolution, metres per LSB (signed 24 bit).
pub const CLASSIC_POS_SCALE: f64 = 1e-5;
/// FD position resolution, metres per LSB (signed 32 bit).
pub const FD_POS_SCALE: f64 = 1e-6;
/// Classic quaternion resolution per LSB (signed 16 bit): 2^-15.
pub const CLASSIC_QUAT_SCALE: f64 = 1.0 / 32768.0;
/// FD quaternion resolution per LSB (signed 32 bit): 2^-30.
pub const FD_QUAT_SCALE: f64 = 1.0 / 1_073_741_824.0;
/// Classic quality resolution per LSB (unsigned 8 bit, raw 0..=250).
pub const CLASSIC_QUALITY_SCALE: f64 = 0.004;
/// FD quality resolution per LSB (unsigned 16 bit, raw 0..=10000).
pub const FD_QUALITY_SCALE: f64 = 0.0001;

const I24_MAX: i64 = (1 << 23) - 1;
const I24_MIN: i64 = -(1 << 23);

/// Which frame of a classic pose set a frame is (its identifier is `base + 4 * object + kind`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ClassicKind {
    /// Position x and y.
    PosXy = 0,
    /// Position z, quality, state, object index.
    PosZStatus = 1,
    /// Quaternion x, y, z.
    QuatXyz = 2,
    /// Quaternion w and the low 32 bits of the pose time.
    QuatWTime = 3,
}

impl ClassicKind {
    /// All kinds in identifier order.
    pub const ALL: [ClassicKind; CLASSIC_FRAMES] = [
        Self::PosXy,
        Self::PosZStatus,
        Self::QuatXyz,
        Self::QuatWTime,
    ];

    fn from_index(i: u16) -> Self {
        Self::ALL[usize::from(i) % CLASSIC_FRAMES]
    }
}

fn put_i24(dst: &mut [u8], v: i64) {
    dst[..3].copy_from_slice(&(v as i32).to_le_bytes()[..3]);
}

fn get_i24(src: &[u8]) -> i64 {
    let v = i32::from_le_bytes([src[0], src[1], src[2], 0]);
    i64::from((v << 8) >> 8)
}

/// Classic identifier of frame `kind` of `object`.
pub fn classic_id(base_id: u16, object: usize, kind: ClassicKind) -> u16 {
    base_id + (object as u16) * CLASSIC_FRAMES as u16 + kind as u16
}

/// FD identifier of `object`.
pub fn fd_id(base_id: u16, object: usize) -> u16 {
    base_id + FD_ID_OFFSET + object as u16
}

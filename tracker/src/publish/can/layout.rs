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

use crate::track::PoseEstimate;
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};

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

/// One CAN or CAN FD frame with inline storage (no allocation).
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct CanFrame {
    /// Identifier without flags (11 bits, or 29 bits when `extended`).
    pub id: u32,
    /// 29-bit extended identifier.
    pub extended: bool,
    /// CAN FD frame (`##` in candump logs).
    pub fd: bool,
    /// FD flags as candump writes them: bit 0 BRS (bit-rate switch), bit 1 ESI (error state indicator).
    pub fd_flags: u8,
    /// Remote transmission request (classic only; data is empty, `len` is the requested length).
    pub remote: bool,
    len: u8,
    data: [u8; 64],
}

impl std::fmt::Debug for CanFrame {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "CanFrame({:X}{}",
            self.id,
            if self.fd { "##" } else { "#" }
        )?;
        for b in self.data() {
            write!(f, "{b:02X}")?;
        }
        write!(f, ")")
    }
}

/// Frame lengths CAN FD allows.
pub const FD_LENGTHS: [usize; 16] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64];

impl CanFrame {
    /// A classic data frame; `None` when `data` is longer than 8 bytes or the identifier does not fit.
    pub fn classic(id: u32, extended: bool, data: &[u8]) -> Option<Self> {
        Self::build(id, extended, false, 0, data)
    }

    /// A CAN FD data frame with candump flags (bit 0 BRS, bit 1 ESI); `None` for a length FD does not allow.
    pub fn fd(id: u32, extended: bool, fd_flags: u8, data: &[u8]) -> Option<Self> {
        if !FD_LENGTHS.contains(&data.len()) {
            return None;
        }
        Self::build(id, extended, true, fd_flags, data)
    }

    /// A classic remote frame asking for `len` (0..=8) bytes.
    pub fn remote(id: u32, extended: bool, len: u8) -> Option<Self> {
        let mut f = Self::build(id, extended, false, 0, &[])?;
        if len > 8 {
            return None;
        }
        f.remote = true;
        f.len = len;
        Some(f)
    }

    fn build(id: u32, extended: bool, fd: bool, fd_flags: u8, data: &[u8]) -> Option<Self> {
        let id_ok = if extended {
            id <= 0x1FFF_FFFF
        } else {
            id <= 0x7FF
        };
        let max = if fd { 64 } else { 8 };
        if !id_ok || data.len() > max {
            return None;
        }
        let mut buf = [0u8; 64];
        buf[..data.len()].copy_from_slice(data);
        Some(Self {
            id,
            extended,
            fd,
            fd_flags,
            remote: false,
            len: data.len() as u8,
            data: buf,
        })
    }

    /// Payload bytes (empty for a remote frame).
    pub fn data(&self) -> &[u8] {
        if self.remote {
            &[]
        } else {
            &self.data[..usize::from(self.len)]
        }
    }

    /// Payload length, or the requested length for a remote frame.
    pub fn len(&self) -> usize {
        usize::from(self.len)
    }

    /// `true` when the frame carries no payload.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    fn blank() -> Self {
        Self {
            id: 0,
            extended: false,
            fd: false,
            fd_flags: 0,
            remote: false,
            len: 0,
            data: [0; 64],
        }
    }
}

// ---------------------------------------------------------------------------------------------------------------
// CRC-8/AUTOSAR

/// CRC-8/AUTOSAR generator polynomial (x^8 + x^5 + x^3 + x^2 + x + 1, normal form).
pub const CRC8_POLY: u8 = 0x2F;
const CRC8_INIT: u8 = 0xFF;
const CRC8_XOROUT: u8 = 0xFF;

const CRC8_TABLE: [u8; 256] = {
    let mut table = [0u8; 256];
    let mut i = 0;
    while i < 256 {
        let mut c = i as u8;
        let mut b = 0;
        while b < 8 {
            c = if c & 0x80 != 0 {
                (c << 1) ^ CRC8_POLY
            } else {
                c << 1
            };
            b += 1;
        }
        table[i] = c;
        i += 1;
    }
    table
};

fn crc8_update(mut crc: u8, bytes: &[u8]) -> u8 {
    for &b in bytes {
        crc = CRC8_TABLE[usize::from(crc ^ b)];
    }
    crc
}

/// CRC-8/AUTOSAR of `bytes` (polynomial 0x2F, init 0xFF, final XOR 0xFF, not reflected).
pub fn crc8_autosar(bytes: &[u8]) -> u8 {
    crc8_update(CRC8_INIT, bytes) ^ CRC8_XOROUT
}

/// The frame CRC: CRC-8/AUTOSAR over the identifier as two bytes (low byte first) followed by `rest`
/// (bytes 1.. of the frame, i.e. everything but the CRC byte itself).
pub fn frame_crc(id: u16, rest: &[u8]) -> u8 {
    let crc = crc8_update(CRC8_INIT, &id.to_le_bytes());
    crc8_update(crc, rest) ^ CRC8_XOROUT
}

// ---------------------------------------------------------------------------------------------------------------
// Encoding

/// Why a pose could not be encoded.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EncodeError {
    /// The object index has no identifiers in the layout.
    #[error("object index {object} is beyond the CAN layout's {MAX_OBJECTS} objects")]
    ObjectIndex {
        /// The object index.
        object: usize,
    },
    /// A field is NaN or infinite.
    #[error("{field} is not finite ({value})")]
    NotFinite {
        /// Field name (e.g. `position x`).
        field: &'static str,
        /// The value.
        value: f64,
    },
    /// A field does not fit its fixed-point range.
    #[error("{field} = {value} is outside the CAN range +-{limit}")]
    OutOfRange {
        /// Field name (e.g. `position x`).
        field: &'static str,
        /// The value.
        value: f64,
        /// Largest magnitude the field can carry.
        limit: f64,
    },
    /// The base identifier leaves the 11-bit identifier space.
    #[error(
        "base id {base_id:#X} is above {MAX_BASE_ID:#X}: the layout's identifiers must stay 11-bit"
    )]
    BaseId {
        /// The base identifier.
        base_id: u16,
    },
}

/// The values one pose puts on the bus, before quantisation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseFields {
    /// Object index (0..[`MAX_OBJECTS`]).
    pub object: usize,
    /// Rolling counter: the tick index mod 256.
    pub counter: u8,
    /// Tick index (FD carries its low 32 bits).
    pub tick_index: u64,
    /// Pose time on the event camera clock, microseconds (classic carries the low 32 bits).
    pub t_us: i64,
    /// Translation of `T_cam_obj`, metres, camera frame.
    pub position: [f64; 3],
    /// Rotation of `T_cam_obj` as a unit quaternion (x, y, z, w).
    pub quaternion: [f64; 4],
    /// Quality in [0, 1].
    pub quality: f32,
    /// State code: 0 tracking, 1 degraded, 2 lost.
    pub state: u8,
}

impl PoseFields {
    /// Fields of `estimate` published at tick `tick_index`.
    pub fn from_estimate(estimate: &PoseEstimate, tick_index: u64) -> Self {
        let t = estimate.pose.translation.vector;
        let q = estimate.pose.rotation.quaternion();
        Self {
            object: estimate.object,
            counter: (tick_index & 0xFF) as u8,
            tick_index,
            t_us: estimate.t_us,
            position: [t.x, t.y, t.z],
            quaternion: [q.i, q.j, q.k, q.w],
            quality: estimate.quality,
            state: estimate.state.code(),
        }
    }
}

fn finite(field: &'static str, value: f64) -> Result<f64, EncodeError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(EncodeError::NotFinite { field, value })
    }
}

fn quantise(
    field: &'static str,
    value: f64,
    scale: f64,
    min: i64,
    max: i64,
) -> Result<i64, EncodeError> {
    let raw = (finite(field, value)? / scale).round();
    if raw < min as f64 || raw > max as f64 {
        return Err(EncodeError::OutOfRange {
            field,
            value,
            limit: max as f64 * scale,
        });
    }
    Ok(raw as i64)
}

const POS_NAMES: [&str; 3] = ["position x", "position y", "position z"];

/// Unit quaternion with `w >= 0` (q and -q are the same rotation), normalised.
fn canonical_quaternion(q: [f64; 4]) -> Result<[f64; 4], EncodeError> {
    for (name, v) in [
        "quaternion x",
        "quaternion y",
        "quaternion z",
        "quaternion w",
    ]
    .iter()
    .zip(q)
    {
        finite(name, v)?;
    }
    let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    if n.is_nan() || n <= 1e-9 {
        return Err(EncodeError::OutOfRange {
            field: "quaternion norm",
            value: n,
            limit: 1.0,
        });
    }
    let s = if q[3] < 0.0 { -1.0 / n } else { 1.0 / n };
    Ok([q[0] * s, q[1] * s, q[2] * s, q[3] * s])
}

fn check_ids(base_id: u16, object: usize) -> Result<(), EncodeError> {
    if base_id > MAX_BASE_ID {
        return Err(EncodeError::BaseId { base_id });
    }
    if object >= MAX_OBJECTS {
        return Err(EncodeError::ObjectIndex { object });
    }
    Ok(())
}

fn quality_raw(q: f32, scale: f64, max: i64) -> Result<i64, EncodeError> {
    let v = finite("quality", f64::from(q))?;
    Ok(((v.clamp(0.0, 1.0) / scale).round() as i64).clamp(0, max))
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

/// Encodes one pose as four classic frames into `out` (in [`ClassicKind`] order).
pub fn encode_classic(
    base_id: u16,
    p: &PoseFields,
    out: &mut [CanFrame; CLASSIC_FRAMES],
) -> Result<(), EncodeError> {
    check_ids(base_id, p.object)?;
    let mut pos = [0i64; 3];
    for i in 0..3 {
        pos[i] = quantise(
            POS_NAMES[i],
            p.position[i],
            CLASSIC_POS_SCALE,
            I24_MIN,
            I24_MAX,
        )?;
    }
    let q = canonical_quaternion(p.quaternion)?;
    let quat = q.map(|c| ((c / CLASSIC_QUAT_SCALE).round() as i64).clamp(-32767, 32767) as i16);
    let quality = quality_raw(p.quality, CLASSIC_QUALITY_SCALE, 250)? as u8;
    if p.state > 2 {
        return Err(EncodeError::OutOfRange {
            field: "state",
            value: f64::from(p.state),
            limit: 2.0,
        });
    }
    for (kind, frame) in ClassicKind::ALL.iter().zip(out.iter_mut()) {
        let id = classic_id(base_id, p.object, *kind);
        let mut d = [0u8; CLASSIC_LEN];
        d[1] = p.counter;
        match kind {
            ClassicKind::PosXy => {
                put_i24(&mut d[2..5], pos[0]);
                put_i24(&mut d[5..8], pos[1]);
            }
            ClassicKind::PosZStatus => {
                put_i24(&mut d[2..5], pos[2]);
                d[5] = quality;
                d[6] = p.state;
                d[7] = p.object as u8;
            }
            ClassicKind::QuatXyz => {
                d[2..4].copy_from_slice(&quat[0].to_le_bytes());
                d[4..6].copy_from_slice(&quat[1].to_le_bytes());
                d[6..8].copy_from_slice(&quat[2].to_le_bytes());
            }
            ClassicKind::QuatWTime => {
                d[2..4].copy_from_slice(&quat[3].to_le_bytes());
                d[4..8].copy_from_slice(&(p.t_us as u32).to_le_bytes());
            }
        }
        d[0] = frame_crc(id, &d[1..]);
        frame.id = u32::from(id);
        frame.extended = false;
        frame.fd = false;
        frame.fd_flags = 0;
        frame.remote = false;
        frame.len = CLASSIC_LEN as u8;
        frame.data[..CLASSIC_LEN].copy_from_slice(&d);
    }
    Ok(())
}

/// Encodes one pose as one 48-byte CAN FD frame into `out` (BRS flag set).
pub fn encode_fd(base_id: u16, p: &PoseFields, out: &mut CanFrame) -> Result<(), EncodeError> {
    check_ids(base_id, p.object)?;
    let mut pos = [0i64; 3];
    for i in 0..3 {
        pos[i] = quantise(
            POS_NAMES[i],
            p.position[i],
            FD_POS_SCALE,
            i64::from(i32::MIN),
            i64::from(i32::MAX),
        )?;
    }
    let q = canonical_quaternion(p.quaternion)?;
    let quat = q.map(|c| {
        (c / FD_QUAT_SCALE)
            .round()
            .clamp(-f64::from(i32::MAX), f64::from(i32::MAX)) as i32
    });
    let quality = quality_raw(p.quality, FD_QUALITY_SCALE, 10_000)? as u16;
    if p.state > 2 {
        return Err(EncodeError::OutOfRange {
            field: "state",
            value: f64::from(p.state),
            limit: 2.0,
        });
    }
    let id = fd_id(base_id, p.object);
    let d = &mut out.data;
    d.fill(0);
    d[1] = p.counter;
    d[2] = p.state;
    d[3] = p.object as u8;
    d[4..6].copy_from_slice(&quality.to_le_bytes());
    d[8..16].copy_from_slice(&p.t_us.to_le_bytes());
    d[16..20].copy_from_slice(&(p.tick_index as u32).to_le_bytes());
    for i in 0..3 {
        d[20 + 4 * i..24 + 4 * i].copy_from_slice(&(pos[i] as i32).to_le_bytes());
    }
    for i in 0..4 {
        d[32 + 4 * i..36 + 4 * i].copy_from_slice(&quat[i].to_le_bytes());
    }
    d[0] = frame_crc(id, &d[1..FD_LEN]);
    out.id = u32::from(id);
    out.extended = false;
    out.fd = true;
    out.fd_flags = 0x01;
    out.remote = false;
    out.len = FD_LEN as u8;
    Ok(())
}

/// Up to four frames of one encoded pose (four classic frames or one FD frame), inline.
#[derive(Clone, Copy, Debug)]
pub struct EncodedPose {
    frames: [CanFrame; CLASSIC_FRAMES],
    count: u8,
}

impl Default for EncodedPose {
    fn default() -> Self {
        Self {
            frames: [CanFrame::blank(); CLASSIC_FRAMES],
            count: 0,
        }
    }
}

impl EncodedPose {
    /// The frames, in transmission order.
    pub fn frames(&self) -> &[CanFrame] {
        &self.frames[..usize::from(self.count)]
    }
}

/// Encodes poses for one bus mode (classic or FD) and base identifier.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PoseEncoder {
    /// Base identifier.
    pub base_id: u16,
    /// `true`: one FD frame per pose; `false`: four classic frames.
    pub fd: bool,
}

impl PoseEncoder {
    /// Encodes `fields` into `out` (overwritten).
    pub fn encode_into(
        &self,
        fields: &PoseFields,
        out: &mut EncodedPose,
    ) -> Result<(), EncodeError> {
        out.count = 0;
        if self.fd {
            encode_fd(self.base_id, fields, &mut out.frames[0])?;
            out.count = 1;
        } else {
            encode_classic(self.base_id, fields, &mut out.frames)?;
            out.count = CLASSIC_FRAMES as u8;
        }
        Ok(())
    }
}

// ---------------------------------------------------------------------------------------------------------------
// Decoding

/// Why a frame was rejected.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum DecodeError {
    /// The identifier is not one of the layout's (for this base identifier).
    #[error("CAN id {id:#X} is not an EventTrack6D pose frame")]
    UnknownId {
        /// Identifier.
        id: u32,
    },
    /// Classic frame on an FD identifier, FD frame on a classic identifier, or a remote frame.
    #[error("CAN id {id:#X}: wrong frame format (expected {expected})")]
    WrongFormat {
        /// Identifier.
        id: u32,
        /// `classic data frame` or `FD data frame`.
        expected: &'static str,
    },
    /// The payload length is not the layout's.
    #[error("CAN id {id:#X}: length {got} bytes, expected {expected}")]
    WrongLength {
        /// Identifier.
        id: u32,
        /// Expected length.
        expected: usize,
        /// Received length.
        got: usize,
    },
    /// The CRC byte does not match the frame.
    #[error("CAN id {id:#X}: bad CRC (frame says {got:#04X}, computed {expected:#04X})")]
    BadCrc {
        /// Identifier.
        id: u32,
        /// CRC computed from the frame.
        expected: u8,
        /// CRC byte in the frame.
        got: u8,
    },
    /// A frame's counter differs from the set being assembled; the incomplete set was discarded.
    #[error(
        "object {object}: counter {got} arrived while assembling counter {expected}; incomplete set discarded"
    )]
    CounterMismatch {
        /// Object index.
        object: usize,
        /// Counter of the discarded set.
        expected: u8,
        /// Counter of the new frame (it starts a new set).
        got: u8,
    },
    /// The object index inside the payload disagrees with the identifier.
    #[error("CAN id {id:#X}: payload says object {in_payload}, identifier says {from_id}")]
    ObjectMismatch {
        /// Identifier.
        id: u32,
        /// Object index from the identifier.
        from_id: usize,
        /// Object index in the payload.
        in_payload: u8,
    },
    /// A field holds a value the layout never sends (state > 2, quality above 1, reserved bits set).
    #[error("CAN id {id:#X}: invalid {field} {value}")]
    InvalidField {
        /// Identifier.
        id: u32,
        /// Field name.
        field: &'static str,
        /// Raw value.
        value: i64,
    },
}

/// Where an identifier sits in the layout.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameSlot {
    /// Classic frame `kind` of `object`.
    Classic {
        /// Object index.
        object: usize,
        /// Which frame of the set.
        kind: ClassicKind,
    },
    /// FD frame of `object`.
    Fd {
        /// Object index.
        object: usize,
    },
}

/// Classifies a frame's identifier under `base_id`.
pub fn classify(base_id: u16, frame: &CanFrame) -> Result<FrameSlot, DecodeError> {
    let unknown = DecodeError::UnknownId { id: frame.id };
    if frame.extended || frame.id < u32::from(base_id) {
        return Err(unknown);
    }
    let off = frame.id - u32::from(base_id);
    if off < u32::from(FD_ID_OFFSET) {
        Ok(FrameSlot::Classic {
            object: (off / CLASSIC_FRAMES as u32) as usize,
            kind: ClassicKind::from_index((off % CLASSIC_FRAMES as u32) as u16),
        })
    } else if off < u32::from(ID_SPAN) {
        Ok(FrameSlot::Fd {
            object: (off - u32::from(FD_ID_OFFSET)) as usize,
        })
    } else {
        Err(unknown)
    }
}

fn check_frame(frame: &CanFrame, fd: bool, len: usize) -> Result<(), DecodeError> {
    if frame.remote || frame.fd != fd {
        let expected = if fd {
            "FD data frame"
        } else {
            "classic data frame"
        };
        return Err(DecodeError::WrongFormat {
            id: frame.id,
            expected,
        });
    }
    let data = frame.data();
    if data.len() != len {
        return Err(DecodeError::WrongLength {
            id: frame.id,
            expected: len,
            got: data.len(),
        });
    }
    let expected = frame_crc(frame.id as u16, &data[1..]);
    if expected != data[0] {
        return Err(DecodeError::BadCrc {
            id: frame.id,
            expected,
            got: data[0],
        });
    }
    Ok(())
}

/// One verified classic frame (CRC checked), not yet combined with the other three.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ClassicPart {
    /// Object index (from the identifier).
    pub object: usize,
    /// Which frame of the set.
    pub kind: ClassicKind,
    /// Rolling counter.
    pub counter: u8,
    /// Bytes 2..8 of the frame.
    pub payload: [u8; 6],
}

/// Verifies and splits one classic frame.
pub fn decode_classic(base_id: u16, frame: &CanFrame) -> Result<ClassicPart, DecodeError> {
    let FrameSlot::Classic { object, kind } = classify(base_id, frame)? else {
        return Err(DecodeError::WrongFormat {
            id: frame.id,
            expected: "classic data frame",
        });
    };
    check_frame(frame, false, CLASSIC_LEN)?;
    let d = frame.data();
    if kind == ClassicKind::PosZStatus {
        if d[7] as usize != object {
            return Err(DecodeError::ObjectMismatch {
                id: frame.id,
                from_id: object,
                in_payload: d[7],
            });
        }
        if d[6] > 2 {
            return Err(DecodeError::InvalidField {
                id: frame.id,
                field: "state",
                value: i64::from(d[6]),
            });
        }
        if d[5] > 250 {
            return Err(DecodeError::InvalidField {
                id: frame.id,
                field: "quality",
                value: i64::from(d[5]),
            });
        }
    }
    let mut payload = [0u8; 6];
    payload.copy_from_slice(&d[2..8]);
    Ok(ClassicPart {
        object,
        kind,
        counter: d[1],
        payload,
    })
}

/// A pose read back from the bus.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DecodedPose {
    /// Object index.
    pub object: usize,
    /// Rolling counter (tick index mod 256).
    pub counter: u8,
    /// Low 32 bits of the pose time, microseconds on the event camera clock (both formats).
    pub t_us_low32: u32,
    /// Full pose time, microseconds (FD only).
    pub t_us: Option<i64>,
    /// Low 32 bits of the tick index (FD only).
    pub tick_index_low32: Option<u32>,
    /// Translation, metres, camera frame.
    pub position: [f64; 3],
    /// Quaternion (x, y, z, w) as sent (w >= 0, unit to within the resolution; not renormalised).
    pub quaternion: [f64; 4],
    /// Quality in [0, 1].
    pub quality: f64,
    /// State code: 0 tracking, 1 degraded, 2 lost.
    pub state: u8,
}

impl DecodedPose {
    /// `T_cam_obj` with the quaternion renormalised.
    pub fn isometry(&self) -> Isometry3<f64> {
        let [x, y, z, w] = self.quaternion;
        let rot = UnitQuaternion::from_quaternion(Quaternion::new(w, x, y, z));
        Isometry3::from_parts(
            Translation3::new(self.position[0], self.position[1], self.position[2]),
            rot,
        )
    }
}

/// Verifies and decodes one FD pose frame.
pub fn decode_fd(base_id: u16, frame: &CanFrame) -> Result<DecodedPose, DecodeError> {
    let FrameSlot::Fd { object } = classify(base_id, frame)? else {
        return Err(DecodeError::WrongFormat {
            id: frame.id,
            expected: "FD data frame",
        });
    };
    check_frame(frame, true, FD_LEN)?;
    let d = frame.data();
    let id = frame.id;
    if d[3] as usize != object {
        return Err(DecodeError::ObjectMismatch {
            id,
            from_id: object,
            in_payload: d[3],
        });
    }
    if d[2] > 2 {
        return Err(DecodeError::InvalidField {
            id,
            field: "state",
            value: i64::from(d[2]),
        });
    }
    let quality = u16::from_le_bytes([d[4], d[5]]);
    if quality > 10_000 {
        return Err(DecodeError::InvalidField {
            id,
            field: "quality",
            value: i64::from(quality),
        });
    }
    let i32_at = |o: usize| i32::from_le_bytes([d[o], d[o + 1], d[o + 2], d[o + 3]]);
    let mut t = [0u8; 8];
    t.copy_from_slice(&d[8..16]);
    let t_us = i64::from_le_bytes(t);
    Ok(DecodedPose {
        object,
        counter: d[1],
        t_us_low32: t_us as u32,
        t_us: Some(t_us),
        tick_index_low32: Some(i32_at(16) as u32),
        position: [0, 1, 2].map(|i| f64::from(i32_at(20 + 4 * i)) * FD_POS_SCALE),
        quaternion: [0, 1, 2, 3].map(|i| f64::from(i32_at(32 + 4 * i)) * FD_QUAT_SCALE),
        quality: f64::from(quality) * FD_QUALITY_SCALE,
        state: d[2],
    })
}

fn combine_classic(object: usize, counter: u8, parts: &[[u8; 6]; CLASSIC_FRAMES]) -> DecodedPose {
    let [a, b, c, e] = parts;
    let i16_at = |p: &[u8; 6], o: usize| {
        f64::from(i16::from_le_bytes([p[o], p[o + 1]])) * CLASSIC_QUAT_SCALE
    };
    DecodedPose {
        object,
        counter,
        t_us_low32: u32::from_le_bytes([e[2], e[3], e[4], e[5]]),
        t_us: None,
        tick_index_low32: None,
        position: [get_i24(&a[0..3]), get_i24(&a[3..6]), get_i24(&b[0..3])]
            .map(|v| v as f64 * CLASSIC_POS_SCALE),
        quaternion: [i16_at(c, 0), i16_at(c, 2), i16_at(c, 4), i16_at(e, 0)],
        quality: f64::from(b[3]) * CLASSIC_QUALITY_SCALE,
        state: b[4],
    }
}

#[derive(Debug, Clone, Copy, Default)]
struct PartialSet {
    counter: u8,
    have: u8,
    parts: [[u8; 6]; CLASSIC_FRAMES],
}

/// What the assembler has seen.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct AssemblerCounters {
    /// Complete, consistent poses returned.
    pub poses: u64,
    /// Frames rejected (unknown id, format, length, CRC, fields).
    pub bad_frames: u64,
    /// Incomplete sets discarded because a frame with another counter arrived.
    pub discarded_sets: u64,
}

/// Reassembles poses from classic frame sets (and passes FD frames through): a pose is returned only when all four
/// frames of one object carry the same counter and a valid CRC.
#[derive(Debug, Clone)]
pub struct Assembler {
    base_id: u16,
    sets: [Option<PartialSet>; MAX_OBJECTS],
    counters: AssemblerCounters,
}

impl Assembler {
    /// An assembler for the layout at `base_id`.
    pub fn new(base_id: u16) -> Self {
        Self {
            base_id,
            sets: [None; MAX_OBJECTS],
            counters: AssemblerCounters::default(),
        }
    }

    /// Counters so far.
    pub fn counters(&self) -> AssemblerCounters {
        self.counters
    }

    /// Feeds one frame. Returns a pose when it completes a consistent set (or is a valid FD frame).
    ///
    /// A [`DecodeError::CounterMismatch`] means the previous incomplete set of that object was discarded; the
    /// frame itself was accepted and starts a new set. Other errors reject the frame and leave sets untouched.
    pub fn push(&mut self, frame: &CanFrame) -> Result<Option<DecodedPose>, DecodeError> {
        let result = self.push_inner(frame);
        match &result {
            Ok(Some(_)) => self.counters.poses += 1,
            Err(DecodeError::CounterMismatch { .. }) => self.counters.discarded_sets += 1,
            Err(_) => self.counters.bad_frames += 1,
            Ok(None) => {}
        }
        result
    }

    fn push_inner(&mut self, frame: &CanFrame) -> Result<Option<DecodedPose>, DecodeError> {
        if let FrameSlot::Fd { .. } = classify(self.base_id, frame)? {
            return decode_fd(self.base_id, frame).map(Some);
        }
        let part = decode_classic(self.base_id, frame)?;
        let slot = &mut self.sets[part.object];
        let mut mismatch = None;
        let set = match slot {
            Some(s) if s.counter == part.counter => s,
            _ => {
                if let Some(old) = slot {
                    mismatch = Some(old.counter);
                }
                slot.insert(PartialSet {
                    counter: part.counter,
                    ..PartialSet::default()
                })
            }
        };
        let bit = 1u8 << (part.kind as u8);
        set.have |= bit;
        set.parts[part.kind as usize] = part.payload;
        if let Some(expected) = mismatch {
            return Err(DecodeError::CounterMismatch {
                object: part.object,
                expected,
                got: part.counter,
            });
        }
        if set.have == 0x0F {
            let pose = combine_classic(part.object, part.counter, &set.parts);
            *slot = None;
            return Ok(Some(pose));
        }
        Ok(None)
    }
}

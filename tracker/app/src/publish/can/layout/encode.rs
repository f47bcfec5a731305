//! Pose to frames: quantisation, range checks and the classic and FD encoders.

use super::*;
use tracker::track::PoseEstimate;

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

/// The position x, y, z quantised with `scale` (metres per LSB) into `min..=max`, in that order.
fn quantise_position(
    position: &[f64; 3],
    scale: f64,
    min: i64,
    max: i64,
) -> Result<[i64; 3], EncodeError> {
    let mut raw = [0i64; 3];
    for (i, r) in raw.iter_mut().enumerate() {
        *r = quantise(POS_NAMES[i], position[i], scale, min, max)?;
    }
    Ok(raw)
}

/// Refuses a state code the layout does not define (0 tracking, 1 degraded, 2 lost).
fn check_state(state: u8) -> Result<(), EncodeError> {
    if state > 2 {
        return Err(EncodeError::OutOfRange {
            field: "state",
            value: f64::from(state),
            limit: 2.0,
        });
    }
    Ok(())
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

/// Encodes one pose as four classic frames into `out` (in [`ClassicKind`] order).
pub fn encode_classic(
    base_id: u16,
    p: &PoseFields,
    out: &mut [CanFrame; CLASSIC_FRAMES],
) -> Result<(), EncodeError> {
    check_ids(base_id, p.object)?;
    let pos = quantise_position(&p.position, CLASSIC_POS_SCALE, I24_MIN, I24_MAX)?;
    let q = canonical_quaternion(p.quaternion)?;
    let quat = q.map(|c| ((c / CLASSIC_QUAT_SCALE).round() as i64).clamp(-32767, 32767) as i16);
    let quality = quality_raw(p.quality, CLASSIC_QUALITY_SCALE, 250)? as u8;
    check_state(p.state)?;
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
        set_header(frame, id, false, CLASSIC_LEN);
        frame.data[..CLASSIC_LEN].copy_from_slice(&d);
    }
    Ok(())
}

/// Encodes one pose as one 48-byte CAN FD frame into `out` (BRS flag set).
pub fn encode_fd(base_id: u16, p: &PoseFields, out: &mut CanFrame) -> Result<(), EncodeError> {
    check_ids(base_id, p.object)?;
    let pos = quantise_position(
        &p.position,
        FD_POS_SCALE,
        i64::from(i32::MIN),
        i64::from(i32::MAX),
    )?;
    let q = canonical_quaternion(p.quaternion)?;
    let quat = q.map(|c| {
        (c / FD_QUAT_SCALE)
            .round()
            .clamp(-f64::from(i32::MAX), f64::from(i32::MAX)) as i32
    });
    let quality = quality_raw(p.quality, FD_QUALITY_SCALE, 10_000)? as u16;
    check_state(p.state)?;
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
    set_header(out, id, true, FD_LEN);
    Ok(())
}

/// Sets the header of one of our data frames: standard 11-bit `id`, `len` payload bytes, and for FD the bit-rate
/// switch (BRS) flag.
fn set_header(frame: &mut CanFrame, id: u16, fd: bool, len: usize) {
    frame.id = u32::from(id);
    frame.extended = false;
    frame.fd = fd;
    frame.fd_flags = if fd { 0x01 } else { 0 };
    frame.remote = false;
    frame.len = len as u8;
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

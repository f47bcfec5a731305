//! Frames to pose: frame classification, checks and the classic and FD decoders.

use super::*;
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};

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

pub(super) fn combine_classic(
    object: usize,
    counter: u8,
    parts: &[[u8; 6]; CLASSIC_FRAMES],
) -> DecodedPose {
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

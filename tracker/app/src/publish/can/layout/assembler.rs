//! Reassembles the four classic frames of a pose, in any order, into one decoded pose.

use super::decode::combine_classic;
use super::*;

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

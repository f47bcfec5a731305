//! Cutting a raw EVT 3.0 word stream into `event_camera_msgs/msg/EventPacket` payloads of about `slice_us` of stream
//! time each, as `metavision_driver` does: the bytes go out unchanged, each packet is the next piece of the stream,
//! and every cut lies on a 16-bit word boundary, right before a time word (TIME_HIGH or TIME_LOW) whose time reaches
//! the end of the packet's window, `slice_us` after the time at the packet's first word that is not a time word. A
//! packet is never cut while it holds only time words. A receiver's decoder, whose state carries across packets,
//! sees the same stream.
//!
//! The slicer follows the stream's time itself, as the drivers' EVT 3.0 decoder does: the 24-bit time base of the
//! TIME_HIGH words wraps (a TIME_HIGH smaller than the previous one by at least 2048 is a wrap; a smaller step is a
//! step back in time), and nothing has a time before the first TIME_HIGH.

/// EVT 3.0 word type (bits 15..12): row address.
const ADDR_Y: u16 = 0x0;
/// EVT 3.0 word type: one CD event at a column.
const ADDR_X: u16 = 0x2;
/// EVT 3.0 word type: base column of the following vector words.
const VECT_BASE_X: u16 = 0x3;
/// EVT 3.0 word type: 12 columns' events as a mask.
const VECT_12: u16 = 0x4;
/// EVT 3.0 word type: 8 columns' events as a mask.
const VECT_8: u16 = 0x5;
/// EVT 3.0 word type: time bits 11..0.
const TIME_LOW: u16 = 0x6;
/// EVT 3.0 word type: time bits 23..12.
const TIME_HIGH: u16 = 0x8;
/// EVT 3.0 word type: an external trigger edge.
const EXT_TRIGGER: u16 = 0xA;
/// A TIME_HIGH smaller than the previous one by at least this much is a wrap of the 24-bit time base.
const WRAP_THRESHOLD: u16 = 2048;

/// The stream time of an EVT 3.0 word stream, microseconds, unwrapped, as the drivers' decoder keeps it.
#[derive(Debug, Clone, Copy, Default)]
struct Evt3Clock {
    /// Whether a TIME_HIGH was seen (before it nothing has a time).
    had_time: bool,
    /// Whether a row (ADDR_Y) and a vector base (VECT_BASE_X) were seen since the time was known.
    row: bool,
    base: bool,
    time_high: u16,
    /// `loop << 24 | high << 12`.
    t_high: i64,
    t: i64,
}

impl Evt3Clock {
    /// The time after `word` if it is a time word that sets the time, without advancing.
    fn time_after(&self, word: u16) -> Option<i64> {
        match word >> 12 {
            TIME_HIGH => {
                let high = word & 0x0FFF;
                let mut loop_base = self.t_high - (i64::from(self.time_high) << 12);
                if self.had_time && high < self.time_high && self.time_high - high >= WRAP_THRESHOLD
                {
                    loop_base += 1 << 24;
                }
                Some(loop_base | (i64::from(high) << 12))
            }
            TIME_LOW if self.had_time => Some(self.t_high | i64::from(word & 0x0FFF)),
            _ => None,
        }
    }

    /// Advances over `word`; returns whether it is a CD event or a trigger edge (at [`Self::time`]).
    fn step(&mut self, word: u16) -> bool {
        if let Some(t) = self.time_after(word) {
            if word >> 12 == TIME_HIGH {
                self.time_high = word & 0x0FFF;
                self.t_high = t;
                self.had_time = true;
            }
            self.t = t;
            return false;
        }
        if !self.had_time {
            return false;
        }
        match word >> 12 {
            ADDR_Y => {
                self.row = true;
                false
            }
            VECT_BASE_X => {
                self.base = true;
                false
            }
            ADDR_X => self.row,
            VECT_12 => self.row && self.base && word & 0x0FFF != 0,
            VECT_8 => self.row && self.base && word & 0x00FF != 0,
            EXT_TRIGGER => true,
            _ => false,
        }
    }

    /// The current stream time, once a TIME_HIGH was seen.
    fn time(&self) -> Option<i64> {
        self.had_time.then_some(self.t)
    }
}

/// One piece of the stream, ready to become an `EventPacket`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Packet {
    /// The stream's bytes, unchanged (an even number, except perhaps a trailing odd byte in the last packet).
    pub bytes: Vec<u8>,
    /// Stream time of the first CD event or trigger edge in the packet, microseconds.
    pub first_event_us: Option<i64>,
    /// Where the packet's window opens: the stream time at its first word that is not a time word (a packet
    /// starts with all the time words before that word; if it starts before the stream's first TIME_HIGH, the time
    /// of that TIME_HIGH), microseconds.
    pub start_us: Option<i64>,
    /// Stream time where the packet ends: the time of the word that starts the next packet, or for the last
    /// packet the stream's last time, microseconds.
    pub end_us: Option<i64>,
}

impl Packet {
    /// The stream time the packet is stamped with: its first event's, or the time at its first word if it has no
    /// event (0 if the stream never gave a time).
    pub fn stamp_us(&self) -> i64 {
        self.first_event_us.or(self.start_us).unwrap_or(0)
    }
}

/// Cuts a raw EVT 3.0 stream, fed in any chunking, into [`Packet`]s of about `slice_us` of stream time.
#[derive(Debug, Clone)]
pub struct Slicer {
    slice_us: i64,
    clock: Evt3Clock,
    bytes: Vec<u8>,
    start_us: Option<i64>,
    first_event_us: Option<i64>,
    /// Whether the packet so far holds only time words (it is then never cut: its window moves on instead).
    only_time_words: bool,
    /// A byte of a word split between two chunks.
    odd: Option<u8>,
}

impl Slicer {
    /// A slicer cutting packets of about `slice_us` microseconds (at least 1).
    pub fn new(slice_us: i64) -> Self {
        Self {
            slice_us: slice_us.max(1),
            clock: Evt3Clock::default(),
            bytes: Vec::new(),
            start_us: None,
            first_event_us: None,
            only_time_words: true,
            odd: None,
        }
    }

    /// Feeds the next bytes of the stream; every packet completed is handed to `emit` (whose error stops the feed).
    pub fn feed<E>(
        &mut self,
        bytes: &[u8],
        emit: &mut impl FnMut(Packet) -> Result<(), E>,
    ) -> Result<(), E> {
        let mut rest = bytes;
        if let Some(lo) = self.odd.take() {
            match rest.split_first() {
                Some((&hi, tail)) => {
                    self.word([lo, hi], emit)?;
                    rest = tail;
                }
                None => {
                    self.odd = Some(lo);
                    return Ok(());
                }
            }
        }
        let mut words = rest.chunks_exact(2);
        for w in &mut words {
            self.word([w[0], w[1]], emit)?;
        }
        self.odd = words.remainder().first().copied();
        Ok(())
    }

    /// Ends the stream: the last packet (with a trailing odd byte, if any), unless the stream was empty.
    pub fn finish(mut self) -> Option<Packet> {
        if let Some(b) = self.odd.take() {
            self.bytes.push(b);
        }
        if self.bytes.is_empty() {
            return None;
        }
        let end = self.clock.time();
        Some(self.take(end))
    }

    fn word<E>(
        &mut self,
        bytes: [u8; 2],
        emit: &mut impl FnMut(Packet) -> Result<(), E>,
    ) -> Result<(), E> {
        let word = u16::from_le_bytes(bytes);
        let new_time = self.clock.time_after(word);
        if let (Some(t), Some(start)) = (new_time, self.start_us)
            && t >= start.saturating_add(self.slice_us)
            && !self.only_time_words
        {
            let packet = self.take(Some(t));
            emit(packet)?;
        }
        if self.bytes.is_empty() {
            self.only_time_words = true;
            self.start_us = self.clock.time();
            self.bytes.reserve(256);
        }
        if self.only_time_words {
            // The window opens at the first word that is not a time word.
            self.start_us = new_time.or(self.start_us);
            self.only_time_words = new_time.is_some();
        } else if self.start_us.is_none() {
            // The packet began before the stream's first TIME_HIGH.
            self.start_us = new_time;
        }
        if self.clock.step(word) && self.first_event_us.is_none() {
            self.first_event_us = self.clock.time();
        }
        self.bytes.extend_from_slice(&bytes);
        Ok(())
    }

    fn take(&mut self, end_us: Option<i64>) -> Packet {
        let capacity = self.bytes.len();
        Packet {
            bytes: std::mem::replace(&mut self.bytes, Vec::with_capacity(capacity)),
            first_event_us: self.first_event_us.take(),
            start_us: self.start_us.take(),
            end_us,
        }
    }
}

#[cfg(test)]
#[path = "slicer_tests.rs"]
mod tests;

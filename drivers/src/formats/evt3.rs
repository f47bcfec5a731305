//! EVT 3.0: 16-bit little-endian words with vectorised CD events (Prophesee IMX636 / Gen4.1 default).
//!
//! Word types (bits 15..12): `0x0` ADDR_Y, `0x2` ADDR_X, `0x3` VECT_BASE_X, `0x4` VECT_12, `0x5` VECT_8,
//! `0x6` TIME_LOW, `0x8` TIME_HIGH, `0xA` EXT_TRIGGER, `0xE` OTHERS, `0x7` CONTINUED_4, `0xF` CONTINUED_12,
//! `0xD` IMU. Time is `loop << 24 | high << 12 | low` microseconds; a TIME_HIGH smaller than the previous one by
//! at least 2048 is a wrap of the 24-bit base. A TIME_LOW smaller than the previous one without a new
//! TIME_HIGH is a small step back in time (the sensor's readout is not strictly ordered), not a wrap.

use super::{EncodeError, Record, TimeHighSteps, WordAssembler, merge_by_time};
use crate::anomaly::{AnomalyKind, DecodeAnomalies};
use crate::event::{CdEvent, EventSink, Geometry, TriggerEdge};

const ADDR_Y: u16 = 0x0;
const ADDR_X: u16 = 0x2;
const VECT_BASE_X: u16 = 0x3;
const VECT_12: u16 = 0x4;
const VECT_8: u16 = 0x5;
const TIME_LOW: u16 = 0x6;
const CONTINUED_4: u16 = 0x7;
const TIME_HIGH: u16 = 0x8;
const EXT_TRIGGER: u16 = 0xA;
const IMU: u16 = 0xD;
const OTHERS: u16 = 0xE;
const CONTINUED_12: u16 = 0xF;

/// Decoder state that must be learnt from the stream before CD events can be placed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Sync {
    /// No TIME_HIGH yet: everything is skipped.
    WaitTime,
    /// Time known, no ADDR_Y yet: CD words are skipped, triggers decode.
    WaitRow,
    /// Fully synchronised.
    Synced,
}

/// Streaming EVT 3.0 decoder. Feed it bytes in any chunking; see the module docs of [`crate::formats`].
#[derive(Debug, Clone)]
pub struct Evt3Decoder {
    limit_x: u32,
    limit_y: u16,
    words: WordAssembler<2>,
    sync: Sync,
    /// `loop << 24` in microseconds.
    loop_base: i64,
    time_high: u16,
    /// `loop_base | high << 12`.
    t_high: i64,
    t: i64,
    y: u16,
    x_base: u32,
    have_base: bool,
    vect_polarity: bool,
    in_vendor_group: bool,
    /// Whether a TIME_HIGH was ever seen (the time base survives a resynchronisation).
    had_time: bool,
    anomalies: DecodeAnomalies,
}

impl Evt3Decoder {
    /// A decoder; with a geometry, events outside it are counted as [`AnomalyKind::OutOfBounds`] and skipped.
    pub fn new(geometry: Option<Geometry>) -> Self {
        let (limit_x, limit_y) = geometry.map_or((2048, 2048), |g| (u32::from(g.width), g.height));
        Self {
            limit_x,
            limit_y,
            words: WordAssembler::default(),
            sync: Sync::WaitTime,
            loop_base: 0,
            time_high: 0,
            t_high: 0,
            t: 0,
            y: 0,
            x_base: 0,
            have_base: false,
            vect_polarity: false,
            in_vendor_group: false,
            had_time: false,
            anomalies: DecodeAnomalies::default(),
        }
    }

    /// Starts a new stream (a camera that was reopened: its time counter restarted): like a fresh decoder, but
    /// the anomaly counters so far are kept.
    pub fn restart(&mut self) {
        self.finish();
        let anomalies = self.anomalies;
        let (limit_x, limit_y) = (self.limit_x, self.limit_y);
        *self = Self::new(None);
        self.limit_x = limit_x;
        self.limit_y = limit_y;
        self.anomalies = anomalies;
    }

    /// Forgets the position in the stream after a gap (bytes lost in transit): a held-back partial word is
    /// counted as [`AnomalyKind::TruncatedWord`], and words are skipped (counted as skipped before sync) until
    /// the next TIME_HIGH and row. The time base is kept, so a wrap of the 24-bit counter during a gap shorter
    /// than about 8 s is still recognised and times stay monotonic.
    pub fn resynchronise(&mut self) {
        self.finish();
        self.sync = Sync::WaitTime;
        self.have_base = false;
        self.in_vendor_group = false;
    }

    /// Counters of skipped words so far.
    pub fn anomalies(&self) -> &DecodeAnomalies {
        &self.anomalies
    }

    /// Timestamp of the most recent time word, microseconds (0 before synchronisation).
    pub fn current_time_us(&self) -> i64 {
        self.t
    }

    /// Decodes the next chunk of the stream.
    pub fn decode<S: EventSink>(&mut self, bytes: &[u8], sink: &mut S) {
        let mut words = std::mem::take(&mut self.words);
        words.feed(bytes, |w| self.word(u16::from_le_bytes(w), sink));
        self.words = words;
    }

    /// Ends the stream: a trailing half word is counted as [`AnomalyKind::TruncatedWord`].
    pub fn finish(&mut self) {
        if self.words.finish() {
            self.anomalies.add(AnomalyKind::TruncatedWord, 1);
        }
    }

    #[inline(always)]
    fn vector<S: EventSink>(&mut self, mask: u32, width: u32, sink: &mut S) {
        if self.sync != Sync::Synced || !self.have_base {
            self.anomalies.skipped_before_sync += 1;
            return;
        }
        let base = self.x_base;
        self.x_base = base + width;
        if mask == 0 {
            return;
        }
        let mut mask = mask;
        if base + width > self.limit_x {
            let keep = self.limit_x.saturating_sub(base);
            let kept = if keep >= 32 {
                mask
            } else {
                mask & ((1u32 << keep) - 1)
            };
            self.anomalies.add(
                AnomalyKind::OutOfBounds,
                u64::from((mask ^ kept).count_ones()),
            );
            mask = kept;
            if mask == 0 {
                return;
            }
        }
        sink.cd_vector(self.t, self.y, base as u16, mask, self.vect_polarity);
    }

    #[inline(always)]
    fn word<S: EventSink>(&mut self, w: u16, sink: &mut S) {
        let kind = w >> 12;
        let was_vendor = self.in_vendor_group;
        if was_vendor {
            self.in_vendor_group = false;
        }
        match kind {
            VECT_12 => self.vector(u32::from(w & 0x0FFF), 12, sink),
            VECT_8 => self.vector(u32::from(w & 0x00FF), 8, sink),
            ADDR_X => {
                if self.sync != Sync::Synced {
                    self.anomalies.skipped_before_sync += 1;
                    return;
                }
                let x = w & 0x07FF;
                if u32::from(x) >= self.limit_x {
                    self.anomalies.add(AnomalyKind::OutOfBounds, 1);
                    return;
                }
                sink.cd(CdEvent {
                    t_us: self.t,
                    x,
                    y: self.y,
                    polarity: w & 0x0800 != 0,
                });
            }
            TIME_LOW => {
                if self.sync == Sync::WaitTime {
                    self.anomalies.skipped_before_sync += 1;
                    return;
                }
                self.t = self.t_high | i64::from(w & 0x0FFF);
            }
            ADDR_Y => {
                if self.sync == Sync::WaitTime {
                    self.anomalies.skipped_before_sync += 1;
                    return;
                }
                let y = w & 0x07FF;
                if y >= self.limit_y {
                    // The row is unusable: events until the next ADDR_Y are out of bounds too.
                    self.anomalies.add(AnomalyKind::OutOfBounds, 1);
                    self.sync = Sync::WaitRow;
                    return;
                }
                self.y = y;
                self.sync = Sync::Synced;
            }
            VECT_BASE_X => {
                if self.sync == Sync::WaitTime {
                    self.anomalies.skipped_before_sync += 1;
                    return;
                }
                self.x_base = u32::from(w & 0x07FF);
                self.vect_polarity = w & 0x0800 != 0;
                self.have_base = true;
            }
            TIME_HIGH => {
                let high = w & 0x0FFF;
                if self.sync == Sync::WaitTime {
                    self.sync = Sync::WaitRow;
                    if self.had_time && high < self.time_high && self.time_high - high >= 2048 {
                        self.loop_base += 1 << 24;
                    }
                    self.had_time = true;
                } else if high < self.time_high {
                    if self.time_high - high >= 2048 {
                        self.loop_base += 1 << 24;
                    } else {
                        self.anomalies.add(AnomalyKind::TimeJumpBack, 1);
                    }
                }
                self.time_high = high;
                self.t_high = self.loop_base | (i64::from(high) << 12);
                self.t = self.t_high;
            }
            EXT_TRIGGER => {
                if self.sync == Sync::WaitTime {
                    self.anomalies.skipped_before_sync += 1;
                    return;
                }
                sink.trigger(TriggerEdge {
                    t_us: self.t,
                    channel: ((w >> 8) & 0x0F) as u8,
                    rising: w & 1 != 0,
                });
            }
            OTHERS | IMU => {
                self.anomalies.ignored_vendor_words += 1;
                self.in_vendor_group = true;
            }
            CONTINUED_4 | CONTINUED_12 => {
                if was_vendor {
                    self.anomalies.ignored_vendor_words += 1;
                    self.in_vendor_group = true;
                } else if self.sync == Sync::WaitTime {
                    self.anomalies.skipped_before_sync += 1;
                } else {
                    self.anomalies.add(AnomalyKind::OrphanContinued, 1);
                }
            }
            _ => {
                if self.sync == Sync::WaitTime {
                    self.anomalies.skipped_before_sync += 1;
                } else {
                    self.anomalies.add(AnomalyKind::UnknownType, 1);
                }
            }
        }
    }
}

/// EVT 3.0 encoder producing what the sensor produces: TIME_HIGH / TIME_LOW words when time changes,
/// ADDR_Y when the row changes, and VECT_BASE_X + VECT_12 / VECT_8 words for consecutive events that share
/// a row, time and polarity with increasing columns; ADDR_X for lone events; EXT_TRIGGER words for triggers.
///
/// Invariant: the decoder applied to the output yields exactly the input records, whatever the chunking.
#[derive(Debug, Clone)]
pub struct Evt3Encoder {
    time: TimeHighSteps,
    low: Option<u16>,
    y: Option<u16>,
}

impl Default for Evt3Encoder {
    fn default() -> Self {
        Self {
            time: TimeHighSteps::new(12, 1 << 12),
            low: None,
            y: None,
        }
    }
}

impl Evt3Encoder {
    /// A fresh encoder (the first record emits a TIME_HIGH).
    pub fn new() -> Self {
        Self::default()
    }

    /// Encodes time-ordered CD events and trigger edges (each slice in its own order; they are merged by
    /// time), appending words to `out`. On error nothing of the offending record is written.
    pub fn encode(
        &mut self,
        cd: &[CdEvent],
        triggers: &[TriggerEdge],
        out: &mut Vec<u8>,
    ) -> Result<(), EncodeError> {
        for record in merge_by_time(cd, triggers) {
            match record {
                Record::Trigger(t) => self.trigger(t, out)?,
                Record::Cd(run) => self.cd_run(run, out)?,
            }
        }
        Ok(())
    }

    fn trigger(&mut self, t: &TriggerEdge, out: &mut Vec<u8>) -> Result<(), EncodeError> {
        if t.channel > 0x0F {
            return Err(EncodeError::ChannelTooLarge {
                channel: t.channel,
                max: 0x0F,
            });
        }
        self.set_time(t.t_us, out)?;
        push(
            out,
            (EXT_TRIGGER << 12) | (u16::from(t.channel) << 8) | u16::from(t.rising),
        );
        Ok(())
    }

    fn cd_run(&mut self, run: &[CdEvent], out: &mut Vec<u8>) -> Result<(), EncodeError> {
        let mut i = 0;
        while i < run.len() {
            let e = run[i];
            if e.x > 0x07FF || e.y > 0x07FF {
                return Err(EncodeError::CoordinateTooLarge {
                    x: e.x,
                    y: e.y,
                    bits: 11,
                });
            }
            // Consecutive events sharing time, row and polarity with strictly increasing columns.
            let mut j = i + 1;
            while j < run.len() {
                let n = run[j];
                if n.t_us != e.t_us || n.y != e.y || n.polarity != e.polarity || n.x <= run[j - 1].x
                {
                    break;
                }
                if n.x > 0x07FF {
                    return Err(EncodeError::CoordinateTooLarge {
                        x: n.x,
                        y: n.y,
                        bits: 11,
                    });
                }
                j += 1;
            }
            self.set_time(e.t_us, out)?;
            if self.y != Some(e.y) {
                push(out, (ADDR_Y << 12) | e.y);
                self.y = Some(e.y);
            }
            let pol = u16::from(e.polarity) << 11;
            if j - i == 1 {
                push(out, (ADDR_X << 12) | pol | e.x);
            } else {
                Self::vectors(&run[i..j], pol, out);
            }
            i = j;
        }
        Ok(())
    }

    /// Emits VECT_BASE_X and vector words for a group of strictly increasing columns on one row.
    fn vectors(group: &[CdEvent], pol: u16, out: &mut Vec<u8>) {
        let mut k = 0;
        let mut base: Option<u16> = None;
        while k < group.len() {
            let b = match base {
                Some(b) if group[k].x < b + 12 => b,
                _ => {
                    let b = group[k].x;
                    push(out, (VECT_BASE_X << 12) | pol | b);
                    b
                }
            };
            let mut mask: u16 = 0;
            while k < group.len() && group[k].x < b + 12 {
                mask |= 1 << (group[k].x - b);
                k += 1;
            }
            if mask < 0x100 {
                push(out, (VECT_8 << 12) | mask);
                base = Some(b + 8);
            } else {
                push(out, (VECT_12 << 12) | mask);
                base = Some(b + 12);
            }
        }
    }

    fn set_time(&mut self, t: i64, out: &mut Vec<u8>) -> Result<(), EncodeError> {
        if self
            .time
            .advance(t, |high| push(out, (TIME_HIGH << 12) | high as u16))?
        {
            self.low = None;
        }
        let low = (t & 0x0FFF) as u16;
        if self.low != Some(low) {
            push(out, (TIME_LOW << 12) | low);
            self.low = Some(low);
        }
        Ok(())
    }
}

#[inline]
fn push(out: &mut Vec<u8>, w: u16) {
    out.extend_from_slice(&w.to_le_bytes());
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::event::EventBuffer;

    fn words(ws: &[u16]) -> Vec<u8> {
        ws.iter().flat_map(|w| w.to_le_bytes()).collect()
    }

    fn decode(bytes: &[u8]) -> (EventBuffer, DecodeAnomalies) {
        let mut d = Evt3Decoder::new(Some(Geometry::new(1280, 720)));
        let mut b = EventBuffer::new();
        d.decode(bytes, &mut b);
        d.finish();
        (b, *d.anomalies())
    }

    #[test]
    fn vector_words_expand_to_columns_and_advance_base() {
        let bytes = words(&[
            0x8001,
            0x6005,
            0x0007,
            0x3800 | 100,
            0x4000 | 0b1000_0000_0101,
            0x5000 | 0b11,
        ]);
        let (b, a) = decode(&bytes);
        let xs: Vec<u16> = b.cd.iter().map(|e| e.x).collect();
        assert_eq!(xs, vec![100, 102, 111, 112, 113]);
        assert!(
            b.cd.iter()
                .all(|e| e.y == 7 && e.polarity && e.t_us == 4096 + 5)
        );
        assert_eq!(a.total(), 0);
    }

    #[test]
    fn words_before_first_time_high_are_skipped_and_counted() {
        let bytes = words(&[0x2005, 0x0003, 0x8000, 0x6001, 0x2006, 0x0004, 0x2007]);
        let (b, a) = decode(&bytes);
        assert_eq!(
            b.cd,
            vec![CdEvent {
                t_us: 1,
                x: 7,
                y: 4,
                polarity: false
            }]
        );
        // ADDR_X, ADDR_Y before TIME_HIGH, then ADDR_X before any row.
        assert_eq!(a.skipped_before_sync, 3);
        assert_eq!(a.total(), 0);
    }

    #[test]
    fn time_high_wrap_and_small_time_low_step_back() {
        let bytes = words(&[
            0x8FFF, 0x6FFE, 0x0001, 0x2001, // t = 0xFFFFFE
            0x8000, 0x6003, 0x2002, // wrap: t = 1 << 24 | 3
            0x6001, 0x2003, // small step back, not a wrap
        ]);
        let (b, a) = decode(&bytes);
        let ts: Vec<i64> = b.cd.iter().map(|e| e.t_us).collect();
        assert_eq!(ts, vec![0xFF_FFFE, (1 << 24) + 3, (1 << 24) + 1]);
        assert_eq!(a.total(), 0);
    }

    #[test]
    fn out_of_bounds_and_unknown_words_are_counted_not_emitted() {
        let bytes = words(&[
            0x8000,
            0x6000,
            0x0001,
            0x2000 | 1300,
            0x3000 | 1275,
            0x4FFF,
            0x1234,
            0x7000,
        ]);
        let (b, a) = decode(&bytes);
        // Vector at 1275..1287 keeps 1275..1279 (5 events), drops 7.
        assert_eq!(b.cd.len(), 5);
        assert_eq!(a.get(AnomalyKind::OutOfBounds), 1 + 7);
        assert_eq!(a.get(AnomalyKind::UnknownType), 1);
        assert_eq!(a.get(AnomalyKind::OrphanContinued), 1);
    }

    #[test]
    fn trailing_half_word_is_counted() {
        let mut bytes = words(&[0x8000, 0x6000]);
        bytes.push(0x12);
        let (_, a) = decode(&bytes);
        assert_eq!(a.get(AnomalyKind::TruncatedWord), 1);
    }

    #[test]
    fn encoder_vectorises_a_row_run() {
        let cd: Vec<CdEvent> = [10u16, 11, 13, 21, 40]
            .iter()
            .map(|&x| CdEvent {
                t_us: 5000,
                x,
                y: 3,
                polarity: true,
            })
            .collect();
        let mut enc = Evt3Encoder::new();
        let mut out = Vec::new();
        enc.encode(&cd, &[], &mut out).unwrap();
        let ws: Vec<u16> = out
            .chunks(2)
            .map(|c| u16::from_le_bytes([c[0], c[1]]))
            .collect();
        assert_eq!(
            ws,
            vec![
                0x8001,
                0x6000 | (5000 - 4096),
                0x0003,
                0x3800 | 10,
                0x4000 | 0b1000_0000_1011,
                0x3800 | 40,
                0x5001
            ]
        );
        let (b, _) = decode(&out);
        assert_eq!(b.cd, cd);
    }

    #[test]
    fn encoder_refuses_time_going_back_across_time_high() {
        let mut enc = Evt3Encoder::new();
        let mut out = Vec::new();
        let a = CdEvent {
            t_us: 10_000,
            x: 1,
            y: 1,
            polarity: true,
        };
        let b = CdEvent { t_us: 100, ..a };
        assert!(matches!(
            enc.encode(&[a, b], &[], &mut out),
            Err(EncodeError::TimeWentBack { .. })
        ));
    }
}

//! EVT 2.1: 64-bit words, CD events vectorised in groups of 32 columns.
//!
//! Word types (bits 63..60): `0x0` EVT_NEG, `0x1` EVT_POS (time bits 5..0 in 59..54, x base in 53..43, y in
//! 42..32, validity mask in 31..0: bit `i` is column `x + i`), `0x8` TIME_HIGH (time bits 33..6 in 59..32),
//! `0xA` EXT_TRIGGER (time bits 5..0 in 59..54, channel in 44..40, value in bit 32), `0xE` OTHERS, `0xF`
//! CONTINUED. Byte order: [`WordOrder::Legacy`] is what the IMX636 sends (the upper 32-bit half first, each
//! half little-endian; `.raw` format string `EVT21;...;endianness=legacy`); [`WordOrder::Little`] is one
//! little-endian 64-bit word (GenX320).

use super::{EncodeError, Record, TimeHighSteps, WordAssembler, merge_by_time};
use crate::anomaly::{AnomalyKind, DecodeAnomalies};
use crate::event::{CdEvent, EventSink, Geometry, TriggerEdge};

const EVT_NEG: u64 = 0x0;
const EVT_POS: u64 = 0x1;
const TIME_HIGH: u64 = 0x8;
const EXT_TRIGGER: u64 = 0xA;
const OTHERS: u64 = 0xE;
const CONTINUED: u64 = 0xF;
const HIGH_MASK: u64 = 0x0FFF_FFFF;

/// How the 64-bit words are laid out in bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum WordOrder {
    /// Upper 32-bit half first, each half little-endian (IMX636).
    #[default]
    Legacy,
    /// Plain little-endian 64-bit words (GenX320).
    Little,
}

impl WordOrder {
    #[inline(always)]
    fn read(self, b: &[u8]) -> u64 {
        match self {
            WordOrder::Little => {
                u64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]])
            }
            WordOrder::Legacy => {
                let first = u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
                let second = u32::from_le_bytes([b[4], b[5], b[6], b[7]]);
                (u64::from(first) << 32) | u64::from(second)
            }
        }
    }

    fn write(self, w: u64, out: &mut Vec<u8>) {
        match self {
            WordOrder::Little => out.extend_from_slice(&w.to_le_bytes()),
            WordOrder::Legacy => {
                out.extend_from_slice(&((w >> 32) as u32).to_le_bytes());
                out.extend_from_slice(&(w as u32).to_le_bytes());
            }
        }
    }
}

/// Streaming EVT 2.1 decoder. Feed it bytes in any chunking.
#[derive(Debug, Clone)]
pub struct Evt21Decoder {
    order: WordOrder,
    limit_x: u32,
    limit_y: u16,
    words: WordAssembler<8>,
    synced: bool,
    loop_base: i64,
    time_high: u64,
    t_high: i64,
    anomalies: DecodeAnomalies,
}

impl Evt21Decoder {
    /// A decoder for the given byte order; with a geometry, events outside it are counted and skipped.
    pub fn new(order: WordOrder, geometry: Option<Geometry>) -> Self {
        let (limit_x, limit_y) = geometry.map_or((2048, 2048), |g| (u32::from(g.width), g.height));
        Self {
            order,
            limit_x,
            limit_y,
            words: WordAssembler::default(),
            synced: false,
            loop_base: 0,
            time_high: 0,
            t_high: 0,
            anomalies: DecodeAnomalies::default(),
        }
    }

    /// Counters of skipped words so far.
    pub fn anomalies(&self) -> &DecodeAnomalies {
        &self.anomalies
    }

    /// Decodes the next chunk of the stream.
    pub fn decode<S: EventSink>(&mut self, bytes: &[u8], sink: &mut S) {
        let mut words = std::mem::take(&mut self.words);
        let order = self.order;
        words.feed(bytes, |w| self.word(order.read(&w), sink));
        self.words = words;
    }

    /// Ends the stream: a trailing partial word is counted as [`AnomalyKind::TruncatedWord`].
    pub fn finish(&mut self) {
        if self.words.finish() {
            self.anomalies.add(AnomalyKind::TruncatedWord, 1);
        }
    }

    #[inline(always)]
    fn word<S: EventSink>(&mut self, w: u64, sink: &mut S) {
        let kind = w >> 60;
        match kind {
            EVT_NEG | EVT_POS => {
                if !self.synced {
                    self.anomalies.skipped_before_sync += 1;
                    return;
                }
                let x = ((w >> 43) & 0x07FF) as u32;
                let y = ((w >> 32) & 0x07FF) as u16;
                let mut mask = w as u32;
                if y >= self.limit_y {
                    self.anomalies
                        .add(AnomalyKind::OutOfBounds, u64::from(mask.count_ones()));
                    return;
                }
                if x + 32 > self.limit_x {
                    let keep = self.limit_x.saturating_sub(x);
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
                }
                if mask != 0 {
                    let t_us = self.t_high | ((w >> 54) & 0x3F) as i64;
                    sink.cd_vector(t_us, y, x as u16, mask, kind == EVT_POS);
                }
            }
            TIME_HIGH => {
                let high = (w >> 32) & HIGH_MASK;
                if !self.synced {
                    self.synced = true;
                } else if high < self.time_high {
                    if self.time_high - high >= 1 << 27 {
                        self.loop_base += 1 << 34;
                    } else {
                        self.anomalies.add(AnomalyKind::TimeJumpBack, 1);
                    }
                }
                self.time_high = high;
                self.t_high = self.loop_base | ((high as i64) << 6);
            }
            EXT_TRIGGER => {
                if !self.synced {
                    self.anomalies.skipped_before_sync += 1;
                    return;
                }
                sink.trigger(TriggerEdge {
                    t_us: self.t_high | ((w >> 54) & 0x3F) as i64,
                    channel: ((w >> 40) & 0x1F) as u8,
                    rising: (w >> 32) & 1 != 0,
                });
            }
            OTHERS | CONTINUED => self.anomalies.ignored_vendor_words += 1,
            _ => {
                if self.synced {
                    self.anomalies.add(AnomalyKind::UnknownType, 1);
                } else {
                    self.anomalies.skipped_before_sync += 1;
                }
            }
        }
    }
}

/// EVT 2.1 encoder: consecutive events sharing time, row and polarity with increasing columns inside one
/// 32-aligned block become one vector word. Invariant: decoding the output yields the input records.
#[derive(Debug, Clone)]
pub struct Evt21Encoder {
    order: WordOrder,
    time: TimeHighSteps,
}

impl Evt21Encoder {
    /// A fresh encoder writing words in `order`.
    pub fn new(order: WordOrder) -> Self {
        Self {
            order,
            time: TimeHighSteps::new(6, (HIGH_MASK + 1) as i64),
        }
    }

    /// Encodes time-ordered CD events and trigger edges, appending words to `out`.
    pub fn encode(
        &mut self,
        cd: &[CdEvent],
        triggers: &[TriggerEdge],
        out: &mut Vec<u8>,
    ) -> Result<(), EncodeError> {
        for record in merge_by_time(cd, triggers) {
            match record {
                Record::Trigger(t) => {
                    if t.channel > 0x1F {
                        return Err(EncodeError::ChannelTooLarge {
                            channel: t.channel,
                            max: 0x1F,
                        });
                    }
                    self.set_time(t.t_us, out)?;
                    let w = (EXT_TRIGGER << 60)
                        | (((t.t_us & 0x3F) as u64) << 54)
                        | (u64::from(t.channel) << 40)
                        | (u64::from(t.rising) << 32);
                    self.order.write(w, out);
                }
                Record::Cd(run) => self.cd_run(run, out)?,
            }
        }
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
            let block = e.x & !31;
            let mut mask = 1u32 << (e.x - block);
            let mut j = i + 1;
            while j < run.len() {
                let n = run[j];
                if n.t_us != e.t_us
                    || n.y != e.y
                    || n.polarity != e.polarity
                    || n.x <= run[j - 1].x
                    || n.x >= block + 32
                {
                    break;
                }
                mask |= 1 << (n.x - block);
                j += 1;
            }
            self.set_time(e.t_us, out)?;
            let w = (u64::from(e.polarity) << 60)
                | (((e.t_us & 0x3F) as u64) << 54)
                | (u64::from(block) << 43)
                | (u64::from(e.y) << 32)
                | u64::from(mask);
            self.order.write(w, out);
            i = j;
        }
        Ok(())
    }

    fn set_time(&mut self, t: i64, out: &mut Vec<u8>) -> Result<(), EncodeError> {
        let order = self.order;
        self.time.advance(t, |high| {
            order.write((TIME_HIGH << 60) | ((high as u64 & HIGH_MASK) << 32), out)
        })?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::event::EventBuffer;

    #[test]
    fn legacy_order_swaps_halves() {
        // The documented example: word 0x0102030405060708 is sent as bytes 04 03 02 01 08 07 06 05.
        let mut out = Vec::new();
        WordOrder::Legacy.write(0x0102_0304_0506_0708, &mut out);
        assert_eq!(out, vec![4, 3, 2, 1, 8, 7, 6, 5]);
        assert_eq!(WordOrder::Legacy.read(&out), 0x0102_0304_0506_0708);
    }

    #[test]
    fn decodes_vector_word() {
        let th = (TIME_HIGH << 60) | (7 << 32);
        let ev = (EVT_POS << 60) | (3 << 54) | (32 << 43) | (9 << 32) | 0b101;
        let mut bytes = Vec::new();
        WordOrder::Legacy.write(th, &mut bytes);
        WordOrder::Legacy.write(ev, &mut bytes);
        let mut d = Evt21Decoder::new(WordOrder::Legacy, None);
        let mut b = EventBuffer::new();
        d.decode(&bytes, &mut b);
        let t = (7 << 6) | 3;
        assert_eq!(
            b.cd,
            vec![
                CdEvent {
                    t_us: t,
                    x: 32,
                    y: 9,
                    polarity: true
                },
                CdEvent {
                    t_us: t,
                    x: 34,
                    y: 9,
                    polarity: true
                }
            ]
        );
    }
}

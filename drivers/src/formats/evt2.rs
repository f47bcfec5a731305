//! EVT 2.0: 32-bit little-endian words, one CD event per word.
//!
//! Word types (bits 31..28): `0x0` CD_OFF, `0x1` CD_ON (x in 21..11, y in 10..0, time bits 5..0 in 27..22),
//! `0x8` TIME_HIGH (time bits 33..6 in 27..0), `0xA` EXT_TRIGGER (value bit 0, channel 12..8, time bits 5..0
//! in 27..22), `0xE` OTHERS, `0xF` CONTINUED. The 34-bit time wraps every ~4.8 hours; a TIME_HIGH smaller than
//! the previous one by at least half its range is a wrap.

use super::{EncodeError, Record, TimeHighSteps, WordAssembler, merge_by_time};
use crate::anomaly::{AnomalyKind, DecodeAnomalies};
use crate::event::{CdEvent, EventSink, Geometry, TriggerEdge};

const CD_OFF: u32 = 0x0;
const CD_ON: u32 = 0x1;
const TIME_HIGH: u32 = 0x8;
const EXT_TRIGGER: u32 = 0xA;
const OTHERS: u32 = 0xE;
const CONTINUED: u32 = 0xF;
const HIGH_MASK: u32 = 0x0FFF_FFFF;

/// Streaming EVT 2.0 decoder. Feed it bytes in any chunking.
#[derive(Debug, Clone)]
pub struct Evt2Decoder {
    limit_x: u16,
    limit_y: u16,
    words: WordAssembler<4>,
    synced: bool,
    loop_base: i64,
    time_high: u32,
    /// `loop_base | high << 6`.
    t_high: i64,
    anomalies: DecodeAnomalies,
}

impl Evt2Decoder {
    /// A decoder; with a geometry, events outside it are counted as [`AnomalyKind::OutOfBounds`] and skipped.
    pub fn new(geometry: Option<Geometry>) -> Self {
        let (limit_x, limit_y) = geometry.map_or((2048, 2048), |g| (g.width, g.height));
        Self {
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
        words.feed(bytes, |w| self.word(u32::from_le_bytes(w), sink));
        self.words = words;
    }

    /// Ends the stream: a trailing partial word is counted as [`AnomalyKind::TruncatedWord`].
    pub fn finish(&mut self) {
        if self.words.finish() {
            self.anomalies.add(AnomalyKind::TruncatedWord, 1);
        }
    }

    #[inline(always)]
    fn word<S: EventSink>(&mut self, w: u32, sink: &mut S) {
        let kind = w >> 28;
        match kind {
            CD_OFF | CD_ON => {
                if !self.synced {
                    self.anomalies.skipped_before_sync += 1;
                    return;
                }
                let x = ((w >> 11) & 0x07FF) as u16;
                let y = (w & 0x07FF) as u16;
                if x >= self.limit_x || y >= self.limit_y {
                    self.anomalies.add(AnomalyKind::OutOfBounds, 1);
                    return;
                }
                let t_us = self.t_high | i64::from((w >> 22) & 0x3F);
                sink.cd(CdEvent {
                    t_us,
                    x,
                    y,
                    polarity: kind == CD_ON,
                });
            }
            TIME_HIGH => {
                let high = w & HIGH_MASK;
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
                self.t_high = self.loop_base | (i64::from(high) << 6);
            }
            EXT_TRIGGER => {
                if !self.synced {
                    self.anomalies.skipped_before_sync += 1;
                    return;
                }
                sink.trigger(TriggerEdge {
                    t_us: self.t_high | i64::from((w >> 22) & 0x3F),
                    channel: ((w >> 8) & 0x1F) as u8,
                    rising: w & 1 != 0,
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

/// EVT 2.0 encoder. Invariant: the decoder applied to the output yields exactly the input records.
#[derive(Debug, Clone)]
pub struct Evt2Encoder {
    time: TimeHighSteps,
}

impl Default for Evt2Encoder {
    fn default() -> Self {
        Self {
            time: TimeHighSteps::new(6, i64::from(HIGH_MASK) + 1),
        }
    }
}

impl Evt2Encoder {
    /// A fresh encoder (the first record emits a TIME_HIGH).
    pub fn new() -> Self {
        Self::default()
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
                    let w = (EXT_TRIGGER << 28)
                        | (((t.t_us & 0x3F) as u32) << 22)
                        | (u32::from(t.channel) << 8)
                        | u32::from(t.rising);
                    out.extend_from_slice(&w.to_le_bytes());
                }
                Record::Cd(run) => {
                    for e in run {
                        if e.x > 0x07FF || e.y > 0x07FF {
                            return Err(EncodeError::CoordinateTooLarge {
                                x: e.x,
                                y: e.y,
                                bits: 11,
                            });
                        }
                        self.set_time(e.t_us, out)?;
                        let w = (u32::from(e.polarity) << 28)
                            | (((e.t_us & 0x3F) as u32) << 22)
                            | (u32::from(e.x) << 11)
                            | u32::from(e.y);
                        out.extend_from_slice(&w.to_le_bytes());
                    }
                }
            }
        }
        Ok(())
    }

    fn set_time(&mut self, t: i64, out: &mut Vec<u8>) -> Result<(), EncodeError> {
        self.time.advance(t, |high| push_high(out, high))?;
        Ok(())
    }
}

fn push_high(out: &mut Vec<u8>, high: i64) {
    let w = (TIME_HIGH << 28) | (high as u32 & HIGH_MASK);
    out.extend_from_slice(&w.to_le_bytes());
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::event::EventBuffer;

    #[test]
    fn decodes_cd_and_trigger_words() {
        let ws: [u32; 4] = [
            0x8000_0002,                                 // t_high = 2 << 6 = 128
            0x1000_0000 | (5 << 22) | (640 << 11) | 479, // ON at (640, 479), t=133
            (63 << 22) | (1 << 11) | 2,                  // OFF at (1, 2), t=191
            0xA000_0000 | (7 << 22) | (3 << 8) | 1,      // rising on channel 3, t=135
        ];
        let bytes: Vec<u8> = ws.iter().flat_map(|w| w.to_le_bytes()).collect();
        let mut d = Evt2Decoder::new(Some(Geometry::new(1280, 720)));
        let mut b = EventBuffer::new();
        for chunk in bytes.chunks(3) {
            d.decode(chunk, &mut b);
        }
        d.finish();
        assert_eq!(
            b.cd,
            vec![
                CdEvent {
                    t_us: 133,
                    x: 640,
                    y: 479,
                    polarity: true
                },
                CdEvent {
                    t_us: 191,
                    x: 1,
                    y: 2,
                    polarity: false
                }
            ]
        );
        assert_eq!(
            b.triggers,
            vec![TriggerEdge {
                t_us: 135,
                channel: 3,
                rising: true
            }]
        );
        assert_eq!(d.anomalies().total(), 0);
    }

    #[test]
    fn time_high_wrap_adds_34_bit_period() {
        let ws: [u32; 4] = [0x8FFF_FFFF, 0x1000_0000, 0x8000_0001, 0x1000_0000];
        let bytes: Vec<u8> = ws.iter().flat_map(|w| w.to_le_bytes()).collect();
        let mut d = Evt2Decoder::new(None);
        let mut b = EventBuffer::new();
        d.decode(&bytes, &mut b);
        assert_eq!(b.cd[0].t_us, 0x0FFF_FFFF << 6);
        assert_eq!(b.cd[1].t_us, (1 << 34) + (1 << 6));
    }
}

//! candump log files: the format `candump -l` writes and `canplayer` reads.
//!
//! One frame per line: `(seconds.micros) iface ID#DATA` for classic frames and `(seconds.micros) iface ID##FDATA`
//! for CAN FD, where `F` is one hex digit of FD flags (bit 0 BRS, bit 1 ESI). Identifiers are 3 hex digits
//! (standard) or 8 (extended); data bytes are upper-case hex without separators. Remote frames are `ID#R` with an
//! optional length digit.

use super::layout::CanFrame;
use std::io::{self, Write};

/// Writes one frame as a candump log line (with the trailing newline) to `out`; no allocation.
pub fn write_line<W: Write>(
    out: &mut W,
    secs: u64,
    micros: u32,
    iface: &str,
    frame: &CanFrame,
) -> io::Result<()> {
    write!(out, "({secs}.{micros:06}) {iface} ")?;
    if frame.extended {
        write!(out, "{:08X}", frame.id)?;
    } else {
        write!(out, "{:03X}", frame.id)?;
    }
    if frame.fd {
        write!(out, "##{:X}", frame.fd_flags & 0x0F)?;
    } else if frame.remote {
        write!(out, "#R")?;
        if !frame.is_empty() {
            write!(out, "{}", frame.len())?;
        }
    } else {
        write!(out, "#")?;
    }
    for b in frame.data() {
        write!(out, "{b:02X}")?;
    }
    writeln!(out)
}

/// One parsed candump line.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CandumpRecord {
    /// Timestamp, whole seconds.
    pub secs: u64,
    /// Timestamp, microseconds within the second.
    pub micros: u32,
    /// Interface name.
    pub iface: String,
    /// The frame.
    pub frame: CanFrame,
}

/// What is wrong with a candump line.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum CandumpError {
    /// The `(seconds.micros)` timestamp is missing or malformed.
    #[error("line {line}: bad timestamp (expected `(seconds.micros)`)")]
    Timestamp {
        /// 1-based line number.
        line: usize,
    },
    /// The interface name or the frame is missing.
    #[error("line {line}: expected `(timestamp) iface ID#DATA`")]
    Fields {
        /// 1-based line number.
        line: usize,
    },
    /// The identifier is not 3 or 8 hex digits, or out of range.
    #[error("line {line}: bad CAN identifier `{id}`")]
    Identifier {
        /// 1-based line number.
        line: usize,
        /// The identifier text.
        id: String,
    },
    /// The data is not an even number of hex digits, too long, or an FD length that does not exist.
    #[error("line {line}: bad frame data: {reason}")]
    Data {
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        reason: &'static str,
    },
}

fn hex_val(c: u8) -> Option<u8> {
    match c {
        b'0'..=b'9' => Some(c - b'0'),
        b'a'..=b'f' => Some(c - b'a' + 10),
        b'A'..=b'F' => Some(c - b'A' + 10),
        _ => None,
    }
}

fn parse_timestamp(s: &str) -> Option<(u64, u32)> {
    let inner = s.strip_prefix('(')?.strip_suffix(')')?;
    let (sec, frac) = inner.split_once('.')?;
    if sec.is_empty()
        || frac.is_empty()
        || frac.len() > 9
        || !sec.bytes().all(|b| b.is_ascii_digit())
    {
        return None;
    }
    if !frac.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    let secs = sec.parse().ok()?;
    // Fractions other than 6 digits are scaled to microseconds.
    let mut micros: u64 = frac.parse().ok()?;
    let digits = frac.len() as u32;
    if digits < 6 {
        micros *= 10u64.pow(6 - digits);
    } else {
        micros /= 10u64.pow(digits - 6);
    }
    Some((secs, micros as u32))
}

fn parse_hex_bytes(s: &str, out: &mut [u8; 64]) -> Option<usize> {
    let b = s.as_bytes();
    if !b.len().is_multiple_of(2) || b.len() / 2 > 64 {
        return None;
    }
    for (i, pair) in b.chunks_exact(2).enumerate() {
        out[i] = (hex_val(pair[0])? << 4) | hex_val(pair[1])?;
    }
    Some(b.len() / 2)
}

/// Parses the frame part of a line (`ID#DATA`, `ID##FDATA`, `ID#R`).
pub fn parse_frame(text: &str, line: usize) -> Result<CanFrame, CandumpError> {
    let data_err = |reason| CandumpError::Data { line, reason };
    let (id_text, rest) = text.split_once('#').ok_or(CandumpError::Fields { line })?;
    let id_err = || CandumpError::Identifier {
        line,
        id: id_text.chars().take(16).collect(),
    };
    let extended = match id_text.len() {
        3 => false,
        8 => true,
        _ => return Err(id_err()),
    };
    if !id_text.bytes().all(|c| hex_val(c).is_some()) {
        return Err(id_err());
    }
    let id = u32::from_str_radix(id_text, 16).map_err(|_| id_err())?;
    let mut buf = [0u8; 64];
    if let Some(fd) = rest.strip_prefix('#') {
        let mut chars = fd.chars();
        let flags = chars
            .next()
            .and_then(|c| c.to_digit(16))
            .ok_or(data_err("missing FD flags digit"))?;
        let n = parse_hex_bytes(chars.as_str(), &mut buf)
            .ok_or(data_err("FD data is not hex bytes"))?;
        CanFrame::fd(id, extended, flags as u8, &buf[..n]).ok_or_else(|| {
            if extended && id > 0x1FFF_FFFF || !extended && id > 0x7FF {
                id_err()
            } else {
                data_err("not a CAN FD length")
            }
        })
    } else if let Some(r) = rest.strip_prefix('R').or_else(|| rest.strip_prefix('r')) {
        let len = match r {
            "" => 0,
            d => d
                .parse::<u8>()
                .map_err(|_| data_err("bad remote frame length"))?,
        };
        CanFrame::remote(id, extended, len).ok_or_else(|| {
            if len > 8 {
                data_err("remote frame length above 8")
            } else {
                id_err()
            }
        })
    } else {
        // A classic frame of 8 bytes may carry a raw DLC 9..15 as `_X`; the payload is still 8 bytes.
        let data = match rest.split_once('_') {
            Some((d, dlc))
                if dlc.len() == 1 && hex_val(dlc.as_bytes()[0]).is_some() && d.len() == 16 =>
            {
                d
            }
            Some(_) => return Err(data_err("bad `_DLC` suffix")),
            None => rest,
        };
        let n = parse_hex_bytes(data, &mut buf).ok_or(data_err("data is not hex bytes"))?;
        if n > 8 {
            return Err(data_err("classic frame longer than 8 bytes"));
        }
        CanFrame::classic(id, extended, &buf[..n]).ok_or_else(id_err)
    }
}

/// Parses one candump log line (1-based `line` for messages). Blank lines are not records: callers skip them.
pub fn parse_line(text: &str, line: usize) -> Result<CandumpRecord, CandumpError> {
    let mut fields = text.split_ascii_whitespace();
    let ts = fields.next().ok_or(CandumpError::Fields { line })?;
    let (secs, micros) = parse_timestamp(ts).ok_or(CandumpError::Timestamp { line })?;
    let iface = fields.next().ok_or(CandumpError::Fields { line })?;
    let frame_text = fields.next().ok_or(CandumpError::Fields { line })?;
    // candump may append a comment (e.g. ` T` / ` R` direction markers); anything after the frame is ignored.
    let frame = parse_frame(frame_text, line)?;
    Ok(CandumpRecord {
        secs,
        micros,
        iface: iface.to_string(),
        frame,
    })
}

/// Parses a whole log; blank lines are skipped, the first bad line is an error.
pub fn parse_log(text: &str) -> Result<Vec<CandumpRecord>, CandumpError> {
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(i, l)| parse_line(l, i + 1))
        .collect()
}

/// Which clock stamps the lines of a [`CandumpSink`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum CandumpClock {
    /// Wall-clock time at writing (as `candump -l` does).
    #[default]
    Wall,
    /// The tick's time on the event camera clock (deterministic logs for replays and tests).
    Camera,
}

/// A [`PoseSink`] writing every pose's frames to a candump log file (buffered; flushed by [`PoseSink::flush`] and on
/// drop).
pub struct CandumpSink {
    name: String,
    iface: String,
    out: io::BufWriter<std::fs::File>,
    encoder: PoseEncoder,
    clock: CandumpClock,
    counters: SinkCounters,
    scratch: EncodedPose,
}

use super::CanError;
use super::layout::{EncodedPose, PoseEncoder, PoseFields};
use crate::publish::{PoseSink, PublishError, SinkCounters, TickPoses};

impl CandumpSink {
    /// Creates (truncates) the log at `path`; lines name interface `iface`.
    pub fn create(
        path: &std::path::Path,
        iface: &str,
        encoder: PoseEncoder,
    ) -> Result<Self, CanError> {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|source| CanError::LogFile {
                path: path.to_path_buf(),
                source,
            })?;
        }
        let file = std::fs::File::create(path).map_err(|source| CanError::LogFile {
            path: path.to_path_buf(),
            source,
        })?;
        Ok(Self {
            name: format!("candump:{}", path.display()),
            iface: iface.to_string(),
            out: io::BufWriter::with_capacity(64 * 1024, file),
            encoder,
            clock: CandumpClock::Wall,
            counters: SinkCounters::default(),
            scratch: EncodedPose::default(),
        })
    }

    /// Chooses the timestamp clock (default: wall clock).
    pub fn with_clock(mut self, clock: CandumpClock) -> Self {
        self.clock = clock;
        self
    }

    fn stamp(&self, t_us: i64) -> (u64, u32) {
        match self.clock {
            CandumpClock::Camera => {
                let t = t_us.max(0) as u64;
                (t / 1_000_000, (t % 1_000_000) as u32)
            }
            CandumpClock::Wall => {
                let d = std::time::SystemTime::now()
                    .duration_since(std::time::UNIX_EPOCH)
                    .unwrap_or_default();
                (d.as_secs(), d.subsec_micros())
            }
        }
    }
}

impl PoseSink for CandumpSink {
    fn name(&self) -> &str {
        &self.name
    }

    fn publish(&mut self, poses: &TickPoses<'_>) -> Result<(), PublishError> {
        let (secs, micros) = self.stamp(poses.tick.t_us);
        let mut first_error: Option<String> = None;
        for est in poses.estimates {
            let fields = PoseFields::from_estimate(est, poses.tick.index);
            let res = self
                .encoder
                .encode_into(&fields, &mut self.scratch)
                .map_err(|e| e.to_string())
                .and_then(|()| {
                    self.scratch
                        .frames()
                        .iter()
                        .try_for_each(|f| write_line(&mut self.out, secs, micros, &self.iface, f))
                        .map_err(|e| format!("write failed: {e}"))
                });
            match res {
                Ok(()) => self.counters.published += 1,
                Err(e) => {
                    self.counters.failed += 1;
                    first_error.get_or_insert_with(|| format!("object {}: {e}", est.object));
                }
            }
        }
        PublishError::from_first(&self.name, first_error)
    }

    fn counters(&self) -> SinkCounters {
        self.counters
    }

    fn flush(&mut self) -> Result<(), PublishError> {
        self.out.flush().map_err(|e| PublishError::Transport {
            sink: self.name.clone(),
            message: format!("flush failed: {e}"),
        })
    }
}

//! Plain-text CD events: one `t_us,x,y,p` line per event (`p` is 1 for ON, 0 for OFF), with an optional
//! header line `t_us,x,y,p`. Trigger edges are not representable in this format.

use crate::event::CdEvent;
use std::io::{self, Write};
use thiserror::Error;

/// The header line written and accepted.
pub const CSV_HEADER: &str = "t_us,x,y,p";

/// A malformed CSV line.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("line {line}: {problem}")]
pub struct CsvLineError {
    /// 1-based line number.
    pub line: u64,
    /// What is wrong with it.
    pub problem: String,
}

/// Streaming parser: feed it bytes in any chunking; complete lines become events.
#[derive(Debug, Default, Clone)]
pub struct EventCsvParser {
    pending: Vec<u8>,
    line: u64,
}

impl EventCsvParser {
    /// A parser at the start of a file.
    pub fn new() -> Self {
        Self::default()
    }

    /// Parses every complete line in `bytes` (plus what was pending), calling `on_event` per event and
    /// `on_error` per malformed line (which is skipped).
    pub fn feed(
        &mut self,
        bytes: &[u8],
        on_event: &mut impl FnMut(CdEvent),
        on_error: &mut impl FnMut(CsvLineError),
    ) {
        let mut rest = bytes;
        while let Some(pos) = rest.iter().position(|&b| b == b'\n') {
            let (head, tail) = rest.split_at(pos);
            rest = &tail[1..];
            if self.pending.is_empty() {
                self.line(head, on_event, on_error);
            } else {
                let mut l = std::mem::take(&mut self.pending);
                l.extend_from_slice(head);
                self.line(&l, on_event, on_error);
                l.clear();
                self.pending = l;
            }
        }
        self.pending.extend_from_slice(rest);
    }

    /// Parses a final line without a newline.
    pub fn finish(
        &mut self,
        on_event: &mut impl FnMut(CdEvent),
        on_error: &mut impl FnMut(CsvLineError),
    ) {
        if !self.pending.is_empty() {
            let l = std::mem::take(&mut self.pending);
            self.line(&l, on_event, on_error);
        }
    }

    fn line(
        &mut self,
        raw: &[u8],
        on_event: &mut impl FnMut(CdEvent),
        on_error: &mut impl FnMut(CsvLineError),
    ) {
        self.line += 1;
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        if raw.iter().all(u8::is_ascii_whitespace) {
            return;
        }
        if self.line == 1 && raw == CSV_HEADER.as_bytes() {
            return;
        }
        match parse_line(raw) {
            Ok(e) => on_event(e),
            Err(problem) => on_error(CsvLineError {
                line: self.line,
                problem,
            }),
        }
    }
}

fn parse_line(raw: &[u8]) -> Result<CdEvent, String> {
    let text = std::str::from_utf8(raw).map_err(|_| "not UTF-8 text".to_string())?;
    let mut fields = text.split(',').map(str::trim);
    let mut next = |name: &str| {
        fields
            .next()
            .ok_or_else(|| format!("missing field `{name}` (expected t_us,x,y,p)"))
    };
    let t = next("t_us")?;
    let x = next("x")?;
    let y = next("y")?;
    let p = next("p")?;
    if fields.next().is_some() {
        return Err("more than 4 fields (expected t_us,x,y,p)".into());
    }
    let t_us: i64 = t
        .parse()
        .map_err(|e: std::num::ParseIntError| match e.kind() {
            std::num::IntErrorKind::PosOverflow | std::num::IntErrorKind::NegOverflow => {
                format!("t_us `{t}` is out of range (microseconds as a 64-bit integer)")
            }
            _ => format!("t_us `{t}` is not an integer"),
        })?;
    let x: u16 = x
        .parse()
        .map_err(|_| format!("x `{x}` is not an integer in 0..65535"))?;
    let y: u16 = y
        .parse()
        .map_err(|_| format!("y `{y}` is not an integer in 0..65535"))?;
    let polarity = match p {
        "1" => true,
        "0" | "-1" => false,
        other => return Err(format!("p `{other}` is not 0, 1 or -1")),
    };
    Ok(CdEvent {
        t_us,
        x,
        y,
        polarity,
    })
}

/// Writes events as CSV lines (no header; call [`write_header`] first if wanted).
pub fn write_events(out: &mut impl Write, events: &[CdEvent]) -> io::Result<()> {
    for e in events {
        writeln!(out, "{},{},{},{}", e.t_us, e.x, e.y, u8::from(e.polarity))?;
    }
    Ok(())
}

/// Writes the header line.
pub fn write_header(out: &mut impl Write) -> io::Result<()> {
    writeln!(out, "{CSV_HEADER}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_lines_across_chunks_and_reports_bad_ones() {
        let text = b"t_us,x,y,p\n10,1,2,1\n11,3,4,0\r\nbad\n12,5,6,2\n13,7,8,1";
        let mut p = EventCsvParser::new();
        let (mut ev, mut err) = (Vec::new(), Vec::new());
        for c in text.chunks(5) {
            p.feed(c, &mut |e| ev.push(e), &mut |e| err.push(e));
        }
        p.finish(&mut |e| ev.push(e), &mut |e| err.push(e));
        assert_eq!(ev.len(), 3);
        assert_eq!(
            ev[1],
            CdEvent {
                t_us: 11,
                x: 3,
                y: 4,
                polarity: false
            }
        );
        assert_eq!(err.iter().map(|e| e.line).collect::<Vec<_>>(), vec![4, 5]);
    }
}

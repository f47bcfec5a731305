//! The `.raw` header: `% key value` lines. Modern files carry `% evt`, `% format`, `% geometry` and `% end`;
//! legacy files only `% evt` and `% plugin_name`, from which the geometry is inferred.

use crate::event::Geometry;
use crate::formats::any::EventFormat;
use crate::formats::evt21::WordOrder;
use std::io::{self, BufRead, Write};
use thiserror::Error;

/// Largest header accepted; anything longer is not a `.raw` header.
const MAX_HEADER_BYTES: usize = 1 << 20;

/// What is wrong with a `.raw` header.
#[derive(Debug, Error)]
pub enum HeaderError {
    /// Reading failed.
    #[error("cannot read header: {0}")]
    Io(io::Error),
    /// The header has neither an `evt` nor a `format` line.
    #[error("header has no `% evt` or `% format` line, so the event format is unknown")]
    NoFormat,
    /// The format is not one this project decodes.
    #[error(
        "unsupported event format `{0}` (supported: EVT3 / evt 3.0, EVT2 / evt 2.0, EVT21 / evt 2.1)"
    )]
    UnsupportedFormat(String),
    /// A line that should carry a number or size does not.
    #[error("bad `{key}` line `{value}`: {problem}")]
    BadValue {
        /// Header key.
        key: String,
        /// Its value.
        value: String,
        /// What is wrong.
        problem: String,
    },
    /// The `evt` and `format` lines disagree.
    #[error("header lines disagree: `evt {evt}` but `format {format}`")]
    Conflict {
        /// The `evt` value.
        evt: String,
        /// The `format` value.
        format: String,
    },
    /// More than [`MAX_HEADER_BYTES`] of `%` lines.
    #[error("header is longer than {MAX_HEADER_BYTES} bytes")]
    TooLong,
}

impl From<io::Error> for HeaderError {
    fn from(e: io::Error) -> Self {
        HeaderError::Io(e)
    }
}

/// A parsed `.raw` header.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RawHeader {
    /// Every `% key value` line in file order (values trimmed; keys may repeat).
    pub fields: Vec<(String, String)>,
    /// The stream encoding.
    pub format: EventFormat,
    /// Sensor size from `geometry`, the `format` options, or inferred from `plugin_name`.
    pub geometry: Option<Geometry>,
    /// Length of the header in bytes: the event stream starts at this offset.
    pub data_offset: u64,
}

impl RawHeader {
    /// A header for writing: `evt`, `format` and `geometry` lines plus `extra` fields.
    pub fn new(format: EventFormat, geometry: Geometry, extra: &[(&str, &str)]) -> Self {
        let mut fields = vec![
            ("evt".to_string(), format.evt_version().to_string()),
            ("format".to_string(), format_value(format, geometry)),
            (
                "geometry".to_string(),
                format!("{}x{}", geometry.width, geometry.height),
            ),
        ];
        fields.extend(extra.iter().map(|(k, v)| (k.to_string(), v.to_string())));
        Self {
            fields,
            format,
            geometry: Some(geometry),
            data_offset: 0,
        }
    }

    /// The first value of `key`.
    pub fn get(&self, key: &str) -> Option<&str> {
        self.fields
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }

    /// Parses the header from the start of `input`, leaving `input` positioned at the first data byte.
    pub fn read(input: &mut impl BufRead) -> Result<Self, HeaderError> {
        let mut fields = Vec::new();
        let mut consumed = 0usize;
        let mut line = Vec::new();
        loop {
            let buf = input.fill_buf()?;
            // Data starts at the first line that does not begin with "% " (a lone "%" line counts as header).
            if buf.is_empty() || buf[0] != b'%' {
                break;
            }
            if buf.len() >= 2 && buf[1] != b' ' && buf[1] != b'\n' && buf[1] != b'\r' {
                break;
            }
            line.clear();
            let n = read_line_bounded(input, &mut line, MAX_HEADER_BYTES - consumed)?;
            consumed += n;
            let text = String::from_utf8_lossy(&line);
            let text = text.trim_end_matches(['\n', '\r']);
            let body = text.strip_prefix('%').unwrap_or(text).trim();
            if body == "end" {
                break;
            }
            if body.is_empty() {
                continue;
            }
            let (key, value) = match body.split_once(char::is_whitespace) {
                Some((k, v)) => (k.to_string(), v.trim().to_string()),
                None => (body.to_string(), String::new()),
            };
            fields.push((key, value));
        }
        let (format, format_geometry) = parse_format(&fields)?;
        let geometry = match fields.iter().find(|(k, _)| k == "geometry") {
            Some((_, v)) => Some(parse_geometry("geometry", v)?),
            None => format_geometry.or_else(|| {
                fields
                    .iter()
                    .find(|(k, _)| k == "plugin_name")
                    .and_then(|(_, v)| geometry_from_plugin(v))
            }),
        };
        Ok(Self {
            fields,
            format,
            geometry,
            data_offset: consumed as u64,
        })
    }

    /// Writes the header (ending with `% end`).
    pub fn write(&self, out: &mut impl Write) -> io::Result<()> {
        for (k, v) in &self.fields {
            if v.is_empty() {
                writeln!(out, "% {k}")?;
            } else {
                writeln!(out, "% {k} {v}")?;
            }
        }
        writeln!(out, "% end")
    }
}

fn read_line_bounded(
    input: &mut impl BufRead,
    line: &mut Vec<u8>,
    budget: usize,
) -> Result<usize, HeaderError> {
    let mut n = 0;
    loop {
        let buf = input.fill_buf()?;
        if buf.is_empty() {
            return Ok(n);
        }
        let (take, done) = match buf.iter().position(|&b| b == b'\n') {
            Some(p) => (p + 1, true),
            None => (buf.len(), false),
        };
        if n + take > budget {
            return Err(HeaderError::TooLong);
        }
        line.extend_from_slice(&buf[..take]);
        input.consume(take);
        n += take;
        if done {
            return Ok(n);
        }
    }
}

fn format_value(format: EventFormat, g: Geometry) -> String {
    let mut s = format!(
        "{};height={};width={}",
        format.format_name(),
        g.height,
        g.width
    );
    if let EventFormat::Evt21(WordOrder::Legacy) = format {
        s.push_str(";endianness=legacy");
    }
    s
}

/// Infers the sensor size from a legacy `plugin_name` (gen3 -> 640x480, gen4 / gen41 / IMX636 -> 1280x720,
/// GenX320 -> 320x320).
pub fn geometry_from_plugin(plugin: &str) -> Option<Geometry> {
    let p = plugin.to_ascii_lowercase();
    if p.contains("genx320") || p.contains("imx8") {
        Some(Geometry::new(320, 320))
    } else if p.contains("gen4")
        || p.contains("imx636")
        || p.contains("imx646")
        || p.contains("evk4")
    {
        Some(Geometry::new(1280, 720))
    } else if p.contains("gen3") {
        Some(Geometry::new(640, 480))
    } else {
        None
    }
}

fn parse_geometry(key: &str, v: &str) -> Result<Geometry, HeaderError> {
    let bad = |problem: &str| HeaderError::BadValue {
        key: key.into(),
        value: v.into(),
        problem: problem.into(),
    };
    let (w, h) = v
        .split_once('x')
        .ok_or_else(|| bad("expected WIDTHxHEIGHT"))?;
    let w: u16 = w
        .trim()
        .parse()
        .map_err(|_| bad("width is not an integer in 1..=2048"))?;
    let h: u16 = h
        .trim()
        .parse()
        .map_err(|_| bad("height is not an integer in 1..=2048"))?;
    check_size(w, h).map_err(bad)
}

fn check_size(w: u16, h: u16) -> Result<Geometry, &'static str> {
    if w == 0 || h == 0 || w > 2048 || h > 2048 {
        return Err("size must be 1..2048 in each dimension");
    }
    Ok(Geometry::new(w, h))
}

fn parse_format(
    fields: &[(String, String)],
) -> Result<(EventFormat, Option<Geometry>), HeaderError> {
    let evt = fields
        .iter()
        .find(|(k, _)| k == "evt")
        .map(|(_, v)| v.as_str());
    let from_evt = match evt {
        None => None,
        Some("3.0" | "3") => Some(EventFormat::Evt3),
        Some("2.0" | "2") => Some(EventFormat::Evt2),
        Some("2.1") => Some(EventFormat::Evt21(WordOrder::Little)),
        Some(other) => return Err(HeaderError::UnsupportedFormat(format!("evt {other}"))),
    };
    let Some((_, fv)) = fields.iter().find(|(k, _)| k == "format") else {
        return from_evt.map(|f| (f, None)).ok_or(HeaderError::NoFormat);
    };
    let mut parts = fv.split(';');
    let name = parts.next().unwrap_or("").trim();
    let mut width = None;
    let mut height = None;
    let mut legacy = false;
    for opt in parts {
        let (k, v) = opt.split_once('=').unwrap_or((opt, ""));
        let num = |v: &str| {
            v.trim().parse::<u16>().map_err(|_| HeaderError::BadValue {
                key: "format".into(),
                value: fv.clone(),
                problem: format!("`{k}` is not an integer"),
            })
        };
        match k.trim() {
            "width" => width = Some(num(v)?),
            "height" => height = Some(num(v)?),
            "endianness" => legacy = v.trim() == "legacy",
            _ => {}
        }
    }
    let format = match name.to_ascii_uppercase().as_str() {
        "EVT3" | "EVT30" | "EVT3.0" => EventFormat::Evt3,
        "EVT2" | "EVT20" | "EVT2.0" => EventFormat::Evt2,
        "EVT21" | "EVT2.1" => EventFormat::Evt21(if legacy {
            WordOrder::Legacy
        } else {
            WordOrder::Little
        }),
        _ => return Err(HeaderError::UnsupportedFormat(name.to_string())),
    };
    if let Some(e) = from_evt
        && std::mem::discriminant(&e) != std::mem::discriminant(&format)
    {
        return Err(HeaderError::Conflict {
            evt: evt.unwrap_or_default().to_string(),
            format: fv.clone(),
        });
    }
    let geometry = match (width, height) {
        (Some(w), Some(h)) => Some(check_size(w, h).map_err(|p| HeaderError::BadValue {
            key: "format".into(),
            value: fv.clone(),
            problem: p.into(),
        })?),
        _ => None,
    };
    Ok((format, geometry))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Cursor;

    #[test]
    fn modern_header_with_end() {
        let bytes = b"% evt 3.0\n% format EVT3;height=720;width=1280\n% geometry 1280x720\n% end\n% x\x00\x80";
        let mut c = Cursor::new(&bytes[..]);
        let h = RawHeader::read(&mut c).unwrap();
        assert_eq!(h.format, EventFormat::Evt3);
        assert_eq!(h.geometry, Some(Geometry::new(1280, 720)));
        // After `% end` everything is data, even bytes that look like a header line.
        assert_eq!(&bytes[h.data_offset as usize..], b"% x\x00\x80");
    }

    #[test]
    fn legacy_header_infers_geometry_from_plugin() {
        let bytes =
            b"% Date 2020-09-25 07:48:31\n% plugin_name hal_plugin_gen3_fx3\n% evt 2.0\n\x01\x02";
        let h = RawHeader::read(&mut Cursor::new(&bytes[..])).unwrap();
        assert_eq!(h.format, EventFormat::Evt2);
        assert_eq!(h.geometry, Some(Geometry::new(640, 480)));
        assert_eq!(h.data_offset as usize, bytes.len() - 2);
    }

    #[test]
    fn evt21_legacy_endianness_option() {
        let bytes = b"% format EVT21;height=720;width=1280;endianness=legacy\n";
        let h = RawHeader::read(&mut Cursor::new(&bytes[..])).unwrap();
        assert_eq!(h.format, EventFormat::Evt21(WordOrder::Legacy));
    }

    #[test]
    fn errors_name_the_problem() {
        let no_fmt = RawHeader::read(&mut Cursor::new(&b"% Date today\n"[..])).unwrap_err();
        assert!(no_fmt.to_string().contains("no `% evt`"));
        let bad =
            RawHeader::read(&mut Cursor::new(&b"% evt 3.0\n% geometry 12x\n"[..])).unwrap_err();
        assert!(bad.to_string().contains("geometry"), "{bad}");
        let unsup = RawHeader::read(&mut Cursor::new(&b"% evt 4.0\n"[..])).unwrap_err();
        assert!(unsup.to_string().contains("unsupported"), "{unsup}");
        let conflict =
            RawHeader::read(&mut Cursor::new(&b"% evt 2.0\n% format EVT3\n"[..])).unwrap_err();
        assert!(matches!(conflict, HeaderError::Conflict { .. }));
    }

    #[test]
    fn written_header_reads_back() {
        let g = Geometry::new(1280, 720);
        let h = RawHeader::new(
            EventFormat::Evt21(WordOrder::Legacy),
            g,
            &[("generator", "test")],
        );
        let mut out = Vec::new();
        h.write(&mut out).unwrap();
        out.extend_from_slice(b"%%");
        let back = RawHeader::read(&mut Cursor::new(&out[..])).unwrap();
        assert_eq!(back.format, h.format);
        assert_eq!(back.geometry, Some(g));
        assert_eq!(back.get("generator"), Some("test"));
        assert_eq!(&out[back.data_offset as usize..], b"%%");
    }
}

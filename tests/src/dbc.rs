//! An independent reader for CAN frames described by a DBC file: the DBC is parsed with the `can-dbc` crate and
//! signals are extracted generically from each signal's start bit, length, byte order, sign, factor and offset.
//! Nothing here uses the tracker's CAN decoder, so tests can check the tracker's frames against the shipped DBC.

use can_dbc::{AttributeDefinition, AttributeValue, AttributeValueType, ByteOrder, Dbc, ValueType};
use std::collections::{BTreeMap, HashMap};

/// One signal's definition, as read from the DBC.
#[derive(Debug, Clone, PartialEq)]
pub struct SignalSpec {
    /// Signal name.
    pub name: String,
    /// DBC start bit (LSB for little endian, MSB in sawtooth numbering for big endian).
    pub start_bit: u64,
    /// Length in bits (1..=64).
    pub size: u64,
    /// `true` for Intel (little-endian) byte order.
    pub little_endian: bool,
    /// Two's-complement signed.
    pub signed: bool,
    /// Physical = raw * factor + offset.
    pub factor: f64,
    /// Physical = raw * factor + offset.
    pub offset: f64,
    /// Unit text.
    pub unit: String,
}

/// One message's definition.
#[derive(Debug, Clone, PartialEq)]
pub struct MessageSpec {
    /// Message name.
    pub name: String,
    /// Length in bytes.
    pub size: u64,
    /// Marked as CAN FD by the `VFrameFormat` attribute (`StandardCAN_FD` / `ExtendedCAN_FD`).
    pub fd: bool,
    /// Signals.
    pub signals: Vec<SignalSpec>,
}

/// A decoded signal: the raw integer and the physical value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SignalValue {
    /// Raw value after sign extension.
    pub raw: i128,
    /// `raw * factor + offset`.
    pub physical: f64,
    /// The signal's factor (its resolution).
    pub factor: f64,
}

/// A DBC database reduced to what decoding needs.
#[derive(Debug, Clone)]
pub struct DbcDecoder {
    messages: HashMap<u32, MessageSpec>,
}

impl SignalSpec {
    /// Extracts the raw value of this signal from `data`; `None` when the signal lies beyond the data.
    pub fn raw(&self, data: &[u8]) -> Option<i128> {
        let bit = |pos: u64| -> Option<u128> {
            let byte = usize::try_from(pos / 8).ok()?;
            Some(u128::from((data.get(byte)? >> (pos % 8)) & 1))
        };
        let mut raw: u128 = 0;
        if self.little_endian {
            for k in 0..self.size {
                raw |= bit(self.start_bit + k)? << k;
            }
        } else {
            // Motorola: start bit is the MSB; walk towards the LSB in sawtooth order.
            let mut pos = self.start_bit;
            for _ in 0..self.size {
                raw = (raw << 1) | bit(pos)?;
                pos = if pos.is_multiple_of(8) {
                    pos + 15
                } else {
                    pos - 1
                };
            }
        }
        let mut v = raw as i128;
        if self.signed && self.size > 0 && (raw >> (self.size - 1)) & 1 == 1 {
            v -= 1i128 << self.size;
        }
        Some(v)
    }
}

impl DbcDecoder {
    /// Parses DBC text.
    pub fn parse(text: &str) -> Result<Self, String> {
        let dbc = Dbc::try_from(text).map_err(|e| format!("DBC parse error: {e:?}"))?;
        let fd_names: Vec<String> = dbc
            .attribute_definitions
            .iter()
            .find_map(|d| match d {
                AttributeDefinition::Message(name, AttributeValueType::Enum(values))
                    if name == "VFrameFormat" =>
                {
                    Some(values.clone())
                }
                _ => None,
            })
            .unwrap_or_default();
        let mut messages = HashMap::new();
        for m in &dbc.messages {
            let fd = match dbc.message_attribute(m.id, "VFrameFormat") {
                Some(AttributeValue::Uint(i)) => fd_names
                    .get(*i as usize)
                    .is_some_and(|n| n.ends_with("CAN_FD")),
                Some(AttributeValue::Int(i)) => fd_names
                    .get(*i as usize)
                    .is_some_and(|n| n.ends_with("CAN_FD")),
                Some(AttributeValue::String(s)) => s.ends_with("CAN_FD"),
                _ => false,
            };
            let signals = m
                .signals
                .iter()
                .map(|s| SignalSpec {
                    name: s.name.clone(),
                    start_bit: s.start_bit,
                    size: s.size,
                    little_endian: s.byte_order == ByteOrder::LittleEndian,
                    signed: s.value_type == ValueType::Signed,
                    factor: s.factor,
                    offset: s.offset,
                    unit: s.unit.clone(),
                })
                .collect();
            let id = m.id.raw() & 0x1FFF_FFFF;
            messages.insert(
                id,
                MessageSpec {
                    name: m.name.clone(),
                    size: m.size,
                    fd,
                    signals,
                },
            );
        }
        Ok(Self { messages })
    }

    /// Reads and parses a DBC file.
    pub fn from_file(path: &std::path::Path) -> Result<Self, String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        Self::parse(&text)
    }

    /// The message with identifier `id`.
    pub fn message(&self, id: u32) -> Option<&MessageSpec> {
        self.messages.get(&id)
    }

    /// All messages by identifier.
    pub fn messages(&self) -> &HashMap<u32, MessageSpec> {
        &self.messages
    }

    /// Decodes every signal of the frame `id`/`data`: `None` for an unknown id, an error for a length mismatch.
    pub fn decode(
        &self,
        id: u32,
        data: &[u8],
    ) -> Option<Result<BTreeMap<String, SignalValue>, String>> {
        let m = self.messages.get(&id)?;
        if data.len() as u64 != m.size {
            return Some(Err(format!(
                "{}: {} bytes, DBC says {}",
                m.name,
                data.len(),
                m.size
            )));
        }
        let mut out = BTreeMap::new();
        for s in &m.signals {
            let Some(raw) = s.raw(data) else {
                return Some(Err(format!("{}.{} lies beyond the frame", m.name, s.name)));
            };
            out.insert(
                s.name.clone(),
                SignalValue {
                    raw,
                    physical: raw as f64 * s.factor + s.offset,
                    factor: s.factor,
                },
            );
        }
        Some(Ok(out))
    }
}

/// Bitwise CRC-8/AUTOSAR (poly 0x2F, init 0xFF, xorout 0xFF) as `docs/can.md` specifies it.
pub fn crc8_autosar(bytes: &[u8]) -> u8 {
    let mut c: u8 = 0xFF;
    for &b in bytes {
        c ^= b;
        for _ in 0..8 {
            c = if c & 0x80 != 0 {
                (c << 1) ^ 0x2F
            } else {
                c << 1
            };
        }
    }
    c ^ 0xFF
}

/// A pose read through the DBC (signal names from `docs/can.md`).
#[derive(Debug, Clone, PartialEq)]
pub struct DbcPose {
    /// Object index (from the message name `ET6D_O<n>_...`).
    pub object: usize,
    /// Rolling counter.
    pub counter: u8,
    /// Low 32 bits of the pose time, microseconds.
    pub t_us_low32: u32,
    /// Full pose time (FD only), microseconds.
    pub t_us: Option<i64>,
    /// Position, metres.
    pub position: [f64; 3],
    /// Quaternion (x, y, z, w).
    pub quaternion: [f64; 4],
    /// Quality.
    pub quality: f64,
    /// State code.
    pub state: u8,
    /// Resolution (DBC factor) of the position, quaternion and quality signals the pose came from.
    pub resolution: [f64; 3],
}

/// Reassembles poses from frames using only the DBC: checks each frame's CRC (id low byte, id high byte, bytes 1..)
/// and combines the four classic messages of an object only when their counters agree.
#[derive(Debug)]
pub struct DbcPoseReader {
    decoder: DbcDecoder,
    partial: HashMap<usize, (u8, BTreeMap<String, SignalValue>, u8)>,
    /// Frames whose CRC did not match.
    pub bad_crc: usize,
    /// Incomplete classic sets dropped because the counter changed.
    pub discarded: usize,
}

fn object_of(name: &str) -> Option<usize> {
    name.strip_prefix("ET6D_O")?.split('_').next()?.parse().ok()
}

impl DbcPoseReader {
    /// A reader over `decoder`.
    pub fn new(decoder: DbcDecoder) -> Self {
        Self {
            decoder,
            partial: HashMap::new(),
            bad_crc: 0,
            discarded: 0,
        }
    }

    /// The decoder.
    pub fn decoder(&self) -> &DbcDecoder {
        &self.decoder
    }

    /// Feeds one frame; returns a pose when one is complete. Errors: unknown id, length, FD marking mismatch.
    pub fn push(&mut self, id: u32, fd: bool, data: &[u8]) -> Result<Option<DbcPose>, String> {
        let m = self
            .decoder
            .message(id)
            .ok_or_else(|| format!("id {id:#X} not in the DBC"))?
            .clone();
        if m.fd != fd {
            return Err(format!("{}: frame fd={fd} but DBC fd={}", m.name, m.fd));
        }
        let sig = self.decoder.decode(id, data).ok_or("unknown id")??;
        let mut crc_in = vec![(id & 0xFF) as u8, (id >> 8) as u8];
        crc_in.extend_from_slice(&data[1..]);
        if sig["CRC"].raw != i128::from(crc8_autosar(&crc_in)) {
            self.bad_crc += 1;
            return Ok(None);
        }
        let object = object_of(&m.name)
            .ok_or_else(|| format!("message name {} has no object index", m.name))?;
        let counter = sig["Counter"].raw as u8;
        if m.fd {
            return Ok(Some(pose_from(object, counter, &sig)));
        }
        let bit = match m.name.rsplit('_').next() {
            Some("PosXY") => 1,
            Some("PosZStatus") => 2,
            Some("QuatXYZ") => 4,
            Some("QuatWTime") => 8,
            _ => return Err(format!("unexpected classic message {}", m.name)),
        };
        let entry = self
            .partial
            .entry(object)
            .or_insert_with(|| (counter, BTreeMap::new(), 0));
        if entry.0 != counter {
            self.discarded += 1;
            *entry = (counter, BTreeMap::new(), 0);
        }
        entry.1.extend(sig);
        entry.2 |= bit;
        if entry.2 == 15 {
            let (_, all, _) = self.partial.remove(&object).unwrap_or_default();
            return Ok(Some(pose_from(object, counter, &all)));
        }
        Ok(None)
    }
}

fn pose_from(object: usize, counter: u8, s: &BTreeMap<String, SignalValue>) -> DbcPose {
    let p = |n: &str| s.get(n).map_or(f64::NAN, |v| v.physical);
    let f = |n: &str| s.get(n).map_or(f64::NAN, |v| v.factor);
    let time = s.get("TimeUs").map_or(0, |v| v.raw);
    DbcPose {
        object,
        counter,
        t_us_low32: time as u32,
        t_us: s.contains_key("TickIndex").then_some(time as i64),
        position: [p("PosX"), p("PosY"), p("PosZ")],
        quaternion: [p("QuatX"), p("QuatY"), p("QuatZ"), p("QuatW")],
        quality: p("Quality"),
        state: s.get("State").map_or(255, |v| v.raw as u8),
        resolution: [f("PosX"), f("QuatW"), f("Quality")],
    }
}

/// Parses one candump log line (`(secs.micros) iface ID#HEX` or `ID##<flags>HEX`) without the tracker's parser:
/// returns (identifier, is FD, data). `None` for anything else (remote frames, malformed lines).
pub fn parse_candump_line(line: &str) -> Option<(u32, bool, Vec<u8>)> {
    let frame = line.split_whitespace().nth(2)?;
    let (id, rest) = frame.split_once('#')?;
    let id = u32::from_str_radix(id, 16).ok()?;
    let (fd, hex) = match rest.strip_prefix('#') {
        Some(r) => (true, r.get(1..)?),
        None => (false, rest),
    };
    if hex.len() % 2 != 0 || !hex.is_ascii() {
        return None;
    }
    let data = (0..hex.len() / 2)
        .map(|i| u8::from_str_radix(&hex[2 * i..2 * i + 2], 16).ok())
        .collect::<Option<_>>()?;
    Some((id, fd, data))
}

/// How the poses of a candump log compare with the pose CSV of the same run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CanCsvMatch {
    /// Poses assembled from the log through the DBC.
    pub can_poses: usize,
    /// Rows in the CSV.
    pub csv_rows: usize,
    /// CAN poses matched to a CSV row (same object, same time) within the DBC resolution.
    pub matched: usize,
    /// Largest position difference, metres.
    pub max_position_error: f64,
    /// Largest quaternion component difference (after making w >= 0).
    pub max_quaternion_error: f64,
}

/// Decodes `candump_log` through the DBC at `dbc` (independently of the tracker: own candump line parser, generic
/// signal extraction, own CRC) and matches every pose with the row of `pose_csv` (`t_us,object,x,y,z,qx,qy,qz,qw,
/// quality,state`, object by name; `objects` gives the names in index order) with the same object and time (full
/// `t_us` for FD, its low 32 bits for classic). Errors: unreadable files, frames the DBC does not describe, bad CRCs,
/// a CAN pose without a CSV row, or any field outside the DBC's resolution.
pub fn check_candump_against_csv(
    dbc: &std::path::Path,
    candump_log: &std::path::Path,
    pose_csv: &std::path::Path,
    objects: &[String],
) -> Result<CanCsvMatch, String> {
    let mut reader = DbcPoseReader::new(DbcDecoder::from_file(dbc)?);
    let log = std::fs::read_to_string(candump_log)
        .map_err(|e| format!("{}: {e}", candump_log.display()))?;
    let mut poses = Vec::new();
    for (i, line) in log
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
    {
        let (id, fd, data) =
            parse_candump_line(line).ok_or_else(|| format!("candump line {}: {line}", i + 1))?;
        if let Some(p) = reader
            .push(id, fd, &data)
            .map_err(|e| format!("candump line {}: {e}", i + 1))?
        {
            poses.push(p);
        }
    }
    if reader.bad_crc > 0 {
        return Err(format!("{} frames with a bad CRC", reader.bad_crc));
    }
    let csv =
        std::fs::read_to_string(pose_csv).map_err(|e| format!("{}: {e}", pose_csv.display()))?;
    let mut rows: HashMap<(usize, u32), Vec<[f64; 9]>> = HashMap::new();
    let mut states: HashMap<(usize, u32), u8> = HashMap::new();
    let mut csv_rows = 0;
    for (i, line) in csv
        .lines()
        .enumerate()
        .skip(1)
        .filter(|(_, l)| !l.trim().is_empty())
    {
        let f: Vec<&str> = line.split(',').collect();
        let bad = || format!("{} line {}: {line}", pose_csv.display(), i + 1);
        if f.len() != 11 {
            return Err(bad());
        }
        let t_us: i64 = f[0].parse().map_err(|_| bad())?;
        let object = objects.iter().position(|o| o == f[1]).ok_or_else(bad)?;
        let mut v = [0.0; 9];
        for (k, x) in f[2..10].iter().enumerate() {
            v[k] = x.parse().map_err(|_| bad())?;
        }
        v[8] = t_us as f64;
        let state = match f[10] {
            "tracking" => 0,
            "degraded" => 1,
            "lost" => 2,
            _ => return Err(bad()),
        };
        rows.entry((object, t_us as u32)).or_default().push(v);
        states.insert((object, t_us as u32), state);
        csv_rows += 1;
    }
    let mut m = CanCsvMatch {
        can_poses: poses.len(),
        csv_rows,
        matched: 0,
        max_position_error: 0.0,
        max_quaternion_error: 0.0,
    };
    for p in &poses {
        let key = (p.object, p.t_us_low32);
        let row = rows.get(&key).and_then(|r| r.first()).ok_or_else(|| {
            format!(
                "CAN pose of object {} at t_us low32 {} has no CSV row",
                p.object, p.t_us_low32
            )
        })?;
        if let Some(t) = p.t_us
            && t as f64 != row[8]
        {
            return Err(format!(
                "object {}: FD time {t} vs CSV {}",
                p.object, row[8]
            ));
        }
        let [pos_res, quat_res, quality_res] = p.resolution;
        for k in 0..3 {
            let e = (p.position[k] - row[k]).abs();
            m.max_position_error = m.max_position_error.max(e);
            if e > pos_res / 2.0 + 1e-9 {
                return Err(format!(
                    "object {} t {}: position {k} {} vs CSV {}",
                    p.object, row[8], p.position[k], row[k]
                ));
            }
        }
        let sign = if row[6] < 0.0 { -1.0 } else { 1.0 };
        for k in 0..4 {
            let e = (p.quaternion[k] - sign * row[3 + k]).abs();
            m.max_quaternion_error = m.max_quaternion_error.max(e);
            if e > quat_res * 1.01 {
                return Err(format!(
                    "object {} t {}: quaternion {k} {} vs CSV {}",
                    p.object,
                    row[8],
                    p.quaternion[k],
                    row[3 + k]
                ));
            }
        }
        if (p.quality - row[7]).abs() > quality_res / 2.0 + 1e-6 {
            return Err(format!(
                "object {} t {}: quality {} vs CSV {}",
                p.object, row[8], p.quality, row[7]
            ));
        }
        if states.get(&key) != Some(&p.state) {
            return Err(format!(
                "object {} t {}: state {} differs from the CSV",
                p.object, row[8], p.state
            ));
        }
        m.matched += 1;
    }
    Ok(m)
}

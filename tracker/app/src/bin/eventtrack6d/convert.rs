//! `eventtrack6d convert`: between EVT 3.0, EVT 2.0, EVT 2.1 and CSV, streaming in constant memory.

use anyhow::{Context, bail};
use clap::{Args, ValueEnum};
use drivers::event::{EventBuffer, Geometry};
use drivers::formats::any::EventFormat;
use drivers::formats::csv::{EventCsvParser, write_events, write_header};
use drivers::formats::evt21::WordOrder;
use drivers::raw::{RawHeader, RawReader, RawWriter};
use std::fs::File;
use std::io::{BufWriter, Read, Write};
use std::path::{Path, PathBuf};

/// Convert an event file between EVT 3.0, EVT 2.0, EVT 2.1 (`.raw`) and CSV (`t_us,x,y,p`).
///
/// The output format is `--to`, or else taken from OUT's extension: `.csv` CSV, `.evt2` EVT 2.0, `.evt21`
/// EVT 2.1, `.raw` / `.evt3` EVT 3.0. The input format is read from the `.raw` header, or CSV for `.csv`.
/// Trigger edges cannot be written to CSV: their count is reported. Streams in constant memory; OUT may not be
/// IN, and a conversion that fails removes its partial OUT. More: docs/event-files.md.
#[derive(Debug, Args)]
pub struct ConvertArgs {
    /// Input file (`.raw` with a header, or `.csv`).
    #[arg(value_name = "IN")]
    pub input: PathBuf,
    /// Output file (overwritten).
    #[arg(value_name = "OUT")]
    pub output: PathBuf,
    /// Output format (default: from OUT's extension).
    #[arg(long, value_enum)]
    pub to: Option<OutputFormat>,
    /// Sensor size `WIDTHxHEIGHT`, 1 to 2048 per side, for a `.raw` written from CSV (default 1280x720; events
    /// outside it are an error). Ignored, with a warning, for a `.raw` input whose header gives its geometry.
    #[arg(long, value_parser = parse_geometry)]
    pub geometry: Option<Geometry>,
}

/// Output encodings.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum OutputFormat {
    /// EVT 3.0 `.raw`.
    Evt3,
    /// EVT 2.0 `.raw`.
    Evt2,
    /// EVT 2.1 `.raw` in the IMX636's (legacy) word order.
    Evt21,
    /// `t_us,x,y,p` text.
    Csv,
}

fn parse_geometry(s: &str) -> Result<Geometry, String> {
    let (w, h) = s
        .split_once('x')
        .ok_or("expected WIDTHxHEIGHT, e.g. 1280x720")?;
    let w: u16 = w
        .parse()
        .map_err(|_| format!("width `{w}` is not an integer"))?;
    let h: u16 = h
        .parse()
        .map_err(|_| format!("height `{h}` is not an integer"))?;
    if w == 0 || h == 0 || w > 2048 || h > 2048 {
        return Err("each dimension must be 1..2048".into());
    }
    Ok(Geometry::new(w, h))
}

/// The format an output file name's extension says, if it names one. `.raw` holds any EVT version (its header
/// says which), so it is `None` here unless `--to` is missing, where it means EVT 3.0.
fn format_of_extension(ext: &str) -> Option<OutputFormat> {
    match ext {
        "csv" => Some(OutputFormat::Csv),
        "evt2" => Some(OutputFormat::Evt2),
        "evt21" => Some(OutputFormat::Evt21),
        "evt3" => Some(OutputFormat::Evt3),
        _ => None,
    }
}

fn output_format(args: &ConvertArgs) -> anyhow::Result<OutputFormat> {
    let ext = args
        .output
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let named = format_of_extension(&ext);
    match (args.to, named) {
        (Some(to), Some(named)) if to != named => bail!(
            "{}: --to {} contradicts the extension `.{ext}`; rename the output or drop --to",
            args.output.display(),
            to.to_possible_value()
                .map_or("?".into(), |v| v.get_name().to_string()),
        ),
        (Some(OutputFormat::Csv), None) if ext == "raw" => bail!(
            "{}: --to csv would write text into a `.raw` file; name the output `.csv`",
            args.output.display()
        ),
        (Some(to), _) => Ok(to),
        (None, Some(named)) => Ok(named),
        (None, None) if ext == "raw" => Ok(OutputFormat::Evt3),
        (None, None) => bail!(
            "{}: cannot tell the output format from the extension `.{ext}`; use --to evt3|evt2|evt21|csv",
            args.output.display()
        ),
    }
}

/// Where converted records go.
enum Sink {
    Csv(BufWriter<File>),
    Raw(RawWriter<BufWriter<File>>),
}

impl Sink {
    fn create(
        path: &Path,
        format: OutputFormat,
        geometry: Geometry,
        source: &str,
    ) -> anyhow::Result<Self> {
        let file =
            File::create(path).with_context(|| format!("{}: cannot create", path.display()))?;
        let mut out = BufWriter::with_capacity(1 << 20, file);
        let encoding = match format {
            OutputFormat::Csv => {
                write_header(&mut out)?;
                return Ok(Sink::Csv(out));
            }
            OutputFormat::Evt3 => EventFormat::Evt3,
            OutputFormat::Evt2 => EventFormat::Evt2,
            OutputFormat::Evt21 => EventFormat::Evt21(WordOrder::Legacy),
        };
        let header = RawHeader::new(encoding, geometry, &[("converted_from", source)]);
        Ok(Sink::Raw(RawWriter::new(out, &header)?))
    }

    /// Writes a batch; returns how many trigger edges could not be written.
    fn write(&mut self, batch: &EventBuffer) -> anyhow::Result<u64> {
        match self {
            Sink::Csv(out) => {
                write_events(out, &batch.cd)?;
                Ok(batch.triggers.len() as u64)
            }
            Sink::Raw(w) => {
                w.write(&batch.cd, &batch.triggers)?;
                Ok(0)
            }
        }
    }

    fn finish(self) -> anyhow::Result<()> {
        match self {
            Sink::Csv(mut out) => out.flush()?,
            Sink::Raw(w) => {
                w.finish()?;
            }
        }
        Ok(())
    }
}

pub fn run(args: &ConvertArgs) -> anyhow::Result<()> {
    crate::paths::check_outputs(
        &[("input", args.input.as_path())],
        &[("output", args.output.as_path())],
    )?;
    let format = output_format(args)?;
    let is_csv_input = args
        .input
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("csv"));
    let total = std::fs::metadata(&args.input)
        .with_context(|| format!("{}", args.input.display()))?
        .len();
    let bar = super::progress::bytes_bar(total, "converting");
    let mut batch = EventBuffer::new();
    let mut dropped_triggers = 0u64;
    let mut events = 0u64;
    let out_path = &args.output;
    // Set once the output is created (truncated): only then is a failed conversion's output ours to remove.
    let mut wrote_output = false;
    let writing = || {
        format!(
            "converting {} to {}",
            args.input.display(),
            out_path.display()
        )
    };
    let mut convert = || -> anyhow::Result<_> {
        Ok(if is_csv_input {
            let geometry = args.geometry.unwrap_or(Geometry::new(1280, 720));
            let mut sink = Sink::create(out_path, format, geometry, "csv")?;
            wrote_output = true;
            let mut input =
                File::open(&args.input).with_context(|| format!("{}", args.input.display()))?;
            let mut parser = EventCsvParser::new();
            let mut buf = vec![0u8; 1 << 20];
            let mut bad: Option<String> = None;
            let mut done = 0u64;
            loop {
                let n = input
                    .read(&mut buf)
                    .with_context(|| format!("{}: read failed", args.input.display()))?;
                let mut on_error = |e: drivers::formats::csv::CsvLineError| {
                    bad.get_or_insert_with(|| e.to_string());
                };
                if n == 0 {
                    parser.finish(&mut |e| batch.cd.push(e), &mut on_error);
                } else {
                    parser.feed(&buf[..n], &mut |e| batch.cd.push(e), &mut on_error);
                }
                if let Some(msg) = bad.take() {
                    bail!("{}: {msg}", args.input.display());
                }
                if let Some(e) = batch
                    .cd
                    .iter()
                    .find(|e| e.x >= geometry.width || e.y >= geometry.height)
                {
                    bail!(
                        "{}: event at ({}, {}) lies outside the {}x{} sensor; pass --geometry",
                        args.input.display(),
                        e.x,
                        e.y,
                        geometry.width,
                        geometry.height
                    );
                }
                events += batch.cd.len() as u64;
                sink.write(&batch).with_context(writing)?;
                batch.clear();
                done += n as u64;
                bar.set_position(done);
                if n == 0 {
                    break;
                }
            }
            sink.finish().with_context(writing)?;
            None
        } else {
            let mut reader = RawReader::open(&args.input)?;
            if let (Some(header), Some(given)) = (reader.header().geometry, args.geometry)
                && header != given
            {
                eprintln!(
                    "warning: --geometry {}x{} ignored: the header of {} says {}x{}",
                    given.width,
                    given.height,
                    args.input.display(),
                    header.width,
                    header.height
                );
            }
            let geometry = reader
                .header()
                .geometry
                .or(args.geometry)
                .unwrap_or(Geometry::new(1280, 720));
            let source = reader.header().format.format_name();
            let mut sink = Sink::create(out_path, format, geometry, source)?;
            wrote_output = true;
            while reader.read_chunk(&mut batch)? {
                events += batch.cd.len() as u64;
                dropped_triggers += sink.write(&batch).with_context(writing)?;
                batch.clear();
                bar.set_position(reader.bytes_read());
            }
            sink.finish().with_context(writing)?;
            Some(*reader.anomalies())
        })
    };
    let result = convert();
    bar.finish_and_clear();
    let anomalies = match result {
        Ok(a) => a,
        Err(e) => {
            // A partial file would read as a shorter recording: remove what this run wrote (it is not the input:
            // checked above), if it is a plain file; a link, a pipe or a device stays.
            let plain = std::fs::symlink_metadata(out_path).is_ok_and(|m| m.file_type().is_file());
            if wrote_output && plain {
                let _ = std::fs::remove_file(out_path);
            }
            return Err(e);
        }
    };
    eprintln!("wrote {events} CD events to {}", out_path.display());
    if dropped_triggers > 0 {
        eprintln!("warning: {dropped_triggers} trigger edges dropped: CSV has no trigger records");
    }
    if let Some(a) = anomalies
        && a.total() + a.skipped_before_sync > 0
    {
        eprintln!(
            "warning: input had {} anomalous words and {} words before synchronisation (skipped; see `eventtrack6d \
             inspect`)",
            a.total(),
            a.skipped_before_sync
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Any `--geometry` text gives a size of 1..=2048 per side or an error; a written size reads back.
        #[test]
        fn any_geometry_text_parses_or_says_why(text in "[0-9x -]{0,12}", w in 1u16..=2048, h in 1u16..=2048) {
            match parse_geometry(&text) {
                Ok(g) => prop_assert!((1..=2048).contains(&g.width) && (1..=2048).contains(&g.height)),
                Err(e) => prop_assert!(!e.is_empty()),
            }
            prop_assert_eq!(parse_geometry(&format!("{w}x{h}")), Ok(Geometry::new(w, h)));
        }
    }

    #[test]
    fn extensions_and_to_must_agree() {
        let args = |out: &str, to: Option<OutputFormat>| ConvertArgs {
            input: "in.raw".into(),
            output: out.into(),
            to,
            geometry: None,
        };
        assert_eq!(
            output_format(&args("x.RAW", None)).unwrap(),
            OutputFormat::Evt3
        );
        assert_eq!(
            output_format(&args("x.evt21", None)).unwrap(),
            OutputFormat::Evt21
        );
        assert_eq!(
            output_format(&args("x.raw", Some(OutputFormat::Evt2))).unwrap(),
            OutputFormat::Evt2
        );
        assert!(output_format(&args("x.raw", Some(OutputFormat::Csv))).is_err());
        assert!(output_format(&args("x.evt2", Some(OutputFormat::Evt3))).is_err());
        assert!(output_format(&args("x.bin", None)).is_err());
        assert_eq!(
            output_format(&args("x.bin", Some(OutputFormat::Csv))).unwrap(),
            OutputFormat::Csv
        );
    }
}

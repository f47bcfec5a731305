//! The per-tick latency log (`[output] latency_log`): one CSV row per tick with where its latency went, so a slow
//! tick in the summary's p99 or max can be found and explained. Written on the tracker thread through a buffer;
//! steady state allocates nothing.

use super::error::RuntimeError;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// The log's header: the columns of [`TickTiming`], durations in microseconds (nanosecond resolution).
pub const LATENCY_LOG_HEADER: &str = "t_us,depth,waited_us,tick_us,sinks_us,latency_us,prepare_us";

/// Where one tick's time went, from the decoding of its trigger edge to the end of the work done after it.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TickTiming {
    /// Tick time, microseconds on the event camera's clock.
    pub t_us: i64,
    /// Whether a depth frame was exposed at this tick.
    pub depth: bool,
    /// Edge decoded -> the tracker's tick starts: the queue, the timeline and the events held back for the tick.
    pub waited: Duration,
    /// The tracker's `tick` call (reconstruction, rendering, refinement).
    pub tick: Duration,
    /// Publishing to every sink.
    pub sinks: Duration,
    /// Edge decoded -> after all sinks: the latency the summary's percentiles count.
    pub latency: Duration,
    /// `prepare_next_tick` after the poses were out (renders started for the next tick); not in `latency`.
    pub prepare: Duration,
}

/// An open latency log.
#[derive(Debug)]
pub struct LatencyLog {
    path: PathBuf,
    out: BufWriter<File>,
    rows: u64,
    /// The first write error; later rows are not written (and not counted).
    failed: Option<String>,
}

impl LatencyLog {
    /// Creates (truncates) `path` and writes the header.
    pub fn create(path: &Path) -> Result<Self, RuntimeError> {
        let failed = |e: std::io::Error| {
            RuntimeError::Output(format!(
                "latency log {}: cannot create: {e}",
                path.display()
            ))
        };
        let file = File::create(path).map_err(failed)?;
        let mut out = BufWriter::with_capacity(1 << 16, file);
        writeln!(out, "{LATENCY_LOG_HEADER}").map_err(failed)?;
        Ok(Self {
            path: path.to_path_buf(),
            out,
            rows: 0,
            failed: None,
        })
    }

    /// Appends one tick's row. After a write error nothing more is written; [`Self::finish`] reports it.
    pub fn record(&mut self, t: &TickTiming) {
        if self.failed.is_some() {
            return;
        }
        let us = |d: Duration| d.as_nanos() as f64 * 1e-3;
        let r = writeln!(
            self.out,
            "{},{},{:.3},{:.3},{:.3},{:.3},{:.3}",
            t.t_us,
            u8::from(t.depth),
            us(t.waited),
            us(t.tick),
            us(t.sinks),
            us(t.latency),
            us(t.prepare)
        );
        match r {
            Ok(()) => self.rows += 1,
            Err(e) => self.failed = Some(format!("latency log {}: {e}", self.path.display())),
        }
    }

    /// Flushes the log; returns the rows written, or the first write error.
    pub fn finish(mut self) -> Result<u64, String> {
        if let Some(e) = self.failed.take() {
            return Err(e);
        }
        self.out
            .flush()
            .map_err(|e| format!("latency log {}: {e}", self.path.display()))?;
        Ok(self.rows)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_tick_is_one_row_of_microseconds_under_the_header() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("latency.csv");
        let mut log = LatencyLog::create(&path).unwrap();
        log.record(&TickTiming {
            t_us: 8_333,
            depth: true,
            waited: Duration::from_nanos(12_345),
            tick: Duration::from_micros(850),
            sinks: Duration::from_micros(40),
            latency: Duration::from_nanos(902_345),
            prepare: Duration::from_micros(30),
        });
        log.record(&TickTiming {
            t_us: 16_666,
            ..TickTiming::default()
        });
        assert_eq!(log.finish(), Ok(2));
        let text = std::fs::read_to_string(&path).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(
            lines,
            [
                LATENCY_LOG_HEADER,
                "8333,1,12.345,850.000,40.000,902.345,30.000",
                "16666,0,0.000,0.000,0.000,0.000,0.000"
            ]
        );
    }

    #[test]
    fn a_log_that_cannot_be_created_names_its_path() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("missing").join("latency.csv");
        let e = LatencyLog::create(&path).unwrap_err().to_string();
        assert!(e.contains("missing/latency.csv"), "{e}");
    }
}

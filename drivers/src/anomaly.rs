//! Counters for malformed or unexpected words in event streams.

use std::fmt;

/// What was wrong with a word (or group of words) that a decoder skipped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum AnomalyKind {
    /// A word whose type field is reserved in the format.
    UnknownType,
    /// A CD event whose column or row lies outside the sensor geometry.
    OutOfBounds,
    /// A time-high word that jumps backwards by less than a wrap but more than the sensor's jitter.
    TimeJumpBack,
    /// An EVT3 `CONTINUED` word that does not follow an `OTHERS` or `IMU` word.
    OrphanContinued,
    /// Bytes left at the end of a stream that do not make a whole word.
    TruncatedWord,
}

impl AnomalyKind {
    /// All kinds, in report order.
    pub const ALL: [AnomalyKind; 5] = [
        AnomalyKind::UnknownType,
        AnomalyKind::OutOfBounds,
        AnomalyKind::TimeJumpBack,
        AnomalyKind::OrphanContinued,
        AnomalyKind::TruncatedWord,
    ];

    /// Stable snake_case name used in reports and JSON.
    pub fn name(self) -> &'static str {
        match self {
            AnomalyKind::UnknownType => "unknown_type",
            AnomalyKind::OutOfBounds => "out_of_bounds",
            AnomalyKind::TimeJumpBack => "time_jump_back",
            AnomalyKind::OrphanContinued => "orphan_continued",
            AnomalyKind::TruncatedWord => "truncated_word",
        }
    }
}

impl fmt::Display for AnomalyKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Per-kind counts of skipped words, plus words skipped before the decoder synchronised.
///
/// Invariant: decoders never stop on bad input; everything they skip is counted here.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct DecodeAnomalies {
    counts: [u64; AnomalyKind::ALL.len()],
    /// Words that need state not yet seen: before the first time-high word, or (EVT3) CD words before the first
    /// row / vector base after it. A stream that starts mid-group does this; it is not an anomaly.
    pub skipped_before_sync: u64,
    /// Vendor words that carry no CD or trigger data (`OTHERS`, `CONTINUED`, `IMU`). Not an anomaly.
    pub ignored_vendor_words: u64,
}

impl DecodeAnomalies {
    /// Adds `n` to the count of `kind`.
    #[inline]
    pub fn add(&mut self, kind: AnomalyKind, n: u64) {
        self.counts[kind as usize] += n;
    }

    /// Count for one kind.
    pub fn get(&self, kind: AnomalyKind) -> u64 {
        self.counts[kind as usize]
    }

    /// Sum over all anomaly kinds (excludes the non-anomalous skip counters).
    pub fn total(&self) -> u64 {
        self.counts.iter().sum()
    }

    /// `(kind, count)` for every kind, including zeros.
    pub fn iter(&self) -> impl Iterator<Item = (AnomalyKind, u64)> + '_ {
        AnomalyKind::ALL.iter().map(|&k| (k, self.get(k)))
    }
}

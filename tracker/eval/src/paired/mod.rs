//! Whether a change moved a suite's scores beyond chance: two benchmark runs of the same sequences (a base and a
//! candidate) paired sequence by sequence, with the mean of the per-sequence differences and its 95 % bootstrap
//! interval (sequences resampled with replacement). The tracker's result on one fast sequence can swing by 50
//! points from a small change, so a suite's mean moves by several points without any real effect; a difference
//! whose interval spans 0 is not one.

mod pairing;
mod report;
mod score;
mod summary;

pub use pairing::{PairingError, RunSide, pair_results};
pub use report::comparison_markdown;
pub use score::PairedScore;
pub use summary::{PairedOptions, PairedSummary, summarise_pairs};

/// Bench `results.json` documents for the tests: one suite, one method, the given scores.
#[cfg(test)]
pub(crate) mod test_runs {
    use super::RunSide;
    use serde_json::{Value, json};

    /// The runs as a side comparing method `eventtrack6d`.
    pub fn side(runs: &[(String, Value)]) -> RunSide<'_> {
        RunSide {
            runs,
            method: "eventtrack6d",
        }
    }

    /// A results.json of `suite` whose `method` scored `scores` (sequence, ADD-S), motion `shake`.
    pub fn run(suite: &str, method: &str, scores: &[(&str, f64)]) -> Value {
        let sequences: serde_json::Map<String, Value> = scores
            .iter()
            .map(|(name, s)| (name.to_string(), json!({"add_s": s, "motion": "shake"})))
            .collect();
        json!({"suite": suite, "methods": {method: {"sequences": sequences}}})
    }
}

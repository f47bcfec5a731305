//! One sequence's scores in the two runs of a comparison.

/// One sequence's ADD-S AUC (percent, 120 Hz) in both runs.
#[derive(Debug, Clone, PartialEq)]
pub struct PairedScore {
    /// The suite the sequence belongs to (as `results.json` names it).
    pub suite: String,
    /// Sequence name.
    pub sequence: String,
    /// Motion profile (`-` where the results do not say).
    pub motion: String,
    /// Score in the base runs, percent (the mean where several runs of the suite are given).
    pub base: f64,
    /// Score in the candidate runs, percent (likewise).
    pub candidate: f64,
    /// Base runs the score is the mean of.
    pub base_runs: usize,
    /// Candidate runs the score is the mean of.
    pub candidate_runs: usize,
}

impl PairedScore {
    /// Candidate minus base, percentage points.
    pub fn difference(&self) -> f64 {
        self.candidate - self.base
    }
}

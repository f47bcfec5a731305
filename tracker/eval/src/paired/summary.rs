//! A set of paired sequences summarised: the means, the mean difference and its bootstrap interval.

use super::score::PairedScore;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A set of paired sequences summarised.
#[derive(Debug, Clone, PartialEq)]
pub struct PairedSummary {
    /// What the set is (`all`, a suite, a motion profile).
    pub label: String,
    /// Sequences in it.
    pub pairs: usize,
    /// Mean base score over the sequences, percent.
    pub base_mean: f64,
    /// Mean candidate score, percent.
    pub candidate_mean: f64,
    /// Mean of the per-sequence differences, points.
    pub mean_difference: f64,
    /// 95 % bootstrap interval of [`Self::mean_difference`] (2.5th and 97.5th percentiles), points.
    pub interval: (f64, f64),
    /// Sequences the candidate raised by more than the `moved` threshold.
    pub raised: usize,
    /// Sequences it lowered by more than the threshold.
    pub lowered: usize,
}

impl PairedSummary {
    /// Whether the interval excludes 0: the difference is more than the draw of sequences explains.
    pub fn is_beyond_chance(&self) -> bool {
        self.interval.0 > 0.0 || self.interval.1 < 0.0
    }
}

/// How [`summarise_pairs`] resamples and what it counts as moved.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairedOptions {
    /// Bootstrap resamples (at least 1).
    pub resamples: usize,
    /// Seed of the resampling: the same seed gives the same interval.
    pub seed: u64,
    /// A sequence counts as raised or lowered when its score moves by more than this, points.
    pub moved: f64,
}

impl Default for PairedOptions {
    fn default() -> Self {
        Self {
            resamples: 10_000,
            seed: 1,
            moved: 10.0,
        }
    }
}

/// The summary of `pairs` under `label`; `None` for an empty set.
pub fn summarise_pairs(
    label: &str,
    pairs: &[&PairedScore],
    options: &PairedOptions,
) -> Option<PairedSummary> {
    if pairs.is_empty() {
        return None;
    }
    let n = pairs.len() as f64;
    let differences: Vec<f64> = pairs.iter().map(|p| p.difference()).collect();
    let mean_difference = differences.iter().sum::<f64>() / n;
    let mut rng = ChaCha8Rng::seed_from_u64(options.seed);
    let mut means: Vec<f64> = (0..options.resamples.max(1))
        .map(|_| {
            (0..pairs.len())
                .map(|_| differences[rng.random_range(0..pairs.len())])
                .sum::<f64>()
                / n
        })
        .collect();
    means.sort_by(f64::total_cmp);
    let at = |q: f64| means[((means.len() - 1) as f64 * q).round() as usize];
    Some(PairedSummary {
        label: label.to_string(),
        pairs: pairs.len(),
        base_mean: pairs.iter().map(|p| p.base).sum::<f64>() / n,
        candidate_mean: pairs.iter().map(|p| p.candidate).sum::<f64>() / n,
        mean_difference,
        interval: (at(0.025), at(0.975)),
        raised: differences.iter().filter(|d| **d > options.moved).count(),
        lowered: differences.iter().filter(|d| **d < -options.moved).count(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::paired::pairing::pair_results;
    use crate::paired::test_runs::{run, side};
    use proptest::prelude::*;

    #[test]
    fn a_constant_shift_has_an_interval_of_exactly_the_shift() {
        let base = [(
            "a".to_string(),
            run(
                "s",
                "eventtrack6d",
                &[("x", 10.0), ("y", 80.0), ("z", 40.0)],
            ),
        )];
        let cand = [(
            "b".to_string(),
            run(
                "s",
                "eventtrack6d",
                &[("x", 15.0), ("y", 85.0), ("z", 45.0)],
            ),
        )];
        let pairs = pair_results(&side(&base), &side(&cand)).unwrap();
        let all: Vec<_> = pairs.iter().collect();
        let s = summarise_pairs("all", &all, &PairedOptions::default()).unwrap();
        assert_eq!(s.pairs, 3);
        assert!((s.mean_difference - 5.0).abs() < 1e-9);
        assert!((s.interval.0 - 5.0).abs() < 1e-9 && (s.interval.1 - 5.0).abs() < 1e-9);
        assert!(s.is_beyond_chance());
        assert_eq!((s.raised, s.lowered), (0, 0));
    }

    proptest! {
        /// The interval holds the mean difference; shifting every candidate score by `c` shifts the mean and the
        /// interval by `c`; the same seed gives the same interval.
        #[test]
        fn the_interval_brackets_the_mean_and_moves_with_a_shift(
            scores in proptest::collection::vec((0.0f64..100.0, 0.0f64..100.0), 1..40),
            c in -20.0f64..20.0,
        ) {
            let make = |shift: f64| -> Vec<PairedScore> {
                scores.iter().enumerate().map(|(i, (b, k))| PairedScore {
                    suite: "s".into(), sequence: format!("q{i}"), motion: "-".into(), base: *b, candidate: k + shift,
                    base_runs: 1, candidate_runs: 1,
                }).collect()
            };
            let options = PairedOptions { resamples: 300, ..PairedOptions::default() };
            let plain = make(0.0);
            let shifted = make(c);
            let s0 = summarise_pairs("all", &plain.iter().collect::<Vec<_>>(), &options).unwrap();
            let s1 = summarise_pairs("all", &shifted.iter().collect::<Vec<_>>(), &options).unwrap();
            prop_assert!(s0.interval.0 <= s0.mean_difference + 1e-9, "{:?}", s0);
            prop_assert!(s0.mean_difference <= s0.interval.1 + 1e-9, "{:?}", s0);
            prop_assert!((s1.mean_difference - s0.mean_difference - c).abs() < 1e-9);
            prop_assert!((s1.interval.0 - s0.interval.0 - c).abs() < 1e-9);
            prop_assert!((s1.interval.1 - s0.interval.1 - c).abs() < 1e-9);
            let again = summarise_pairs("all", &plain.iter().collect::<Vec<_>>(), &options).unwrap();
            prop_assert_eq!(again, s0);
        }
    }
}

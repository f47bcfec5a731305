//! Whether a change moved a suite's scores beyond chance: two benchmark runs of the same sequences (a base and a
//! candidate) paired sequence by sequence, with the mean of the per-sequence differences and its 95 % bootstrap
//! interval (sequences resampled with replacement). The tracker's result on one fast sequence can swing by 50
//! points from a small change, so a suite's mean moves by several points without any real effect; a difference
//! whose interval spans 0 is not one.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::Value;
use std::collections::BTreeMap;

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

/// What is wrong with the runs given to [`pair_results`].
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum PairingError {
    /// A document is not the `results.json` a bench writes.
    #[error("{0}: not a bench results.json ({1})")]
    NotResults(String, String),
    /// A run lacks the method asked for.
    #[error("{file}: no method `{method}` (it has: {have})")]
    NoMethod {
        /// The file.
        file: String,
        /// The method asked for.
        method: String,
        /// The methods it has.
        have: String,
    },
    /// A sequence has no usable score.
    #[error("{file}: sequence `{sequence}` has no finite add_s")]
    BadScore {
        /// The file.
        file: String,
        /// The sequence.
        sequence: String,
    },
    /// The same run is given twice on one side.
    #[error("{file} is given twice as {side}")]
    Duplicate {
        /// The file.
        file: String,
        /// `base` or `candidate`.
        side: &'static str,
    },
    /// The two sides do not hold the same sequences.
    #[error(
        "the runs do not hold the same sequences: only in base: {only_base}; only in candidate: {only_candidate}"
    )]
    Unpaired {
        /// Up to ten `suite/sequence` names only the base has.
        only_base: String,
        /// Up to ten only the candidate has.
        only_candidate: String,
    },
}

/// One side's runs: each `(file name, results.json document)`, and the method whose scores to read.
pub struct RunSide<'a> {
    /// The runs.
    pub runs: &'a [(String, Value)],
    /// Method name (a key of `methods`).
    pub method: &'a str,
}

/// Per `(suite, sequence)`: motion profile, sum of the runs' scores, runs.
type Scores = BTreeMap<(String, String), (String, f64, usize)>;

fn side_scores(side: &RunSide<'_>, label: &'static str) -> Result<Scores, PairingError> {
    let mut scores = Scores::new();
    for (k, (file, doc)) in side.runs.iter().enumerate() {
        if side.runs[..k].iter().any(|(other, _)| other == file) {
            return Err(PairingError::Duplicate {
                file: file.clone(),
                side: label,
            });
        }
        let not_results = |why: &str| PairingError::NotResults(file.clone(), why.to_string());
        let suite = doc
            .get("suite")
            .and_then(Value::as_str)
            .ok_or_else(|| not_results("no `suite` string"))?;
        let methods = doc
            .get("methods")
            .and_then(Value::as_object)
            .ok_or_else(|| not_results("no `methods` object"))?;
        let method = methods
            .get(side.method)
            .ok_or_else(|| PairingError::NoMethod {
                file: file.clone(),
                method: side.method.to_string(),
                have: methods.keys().cloned().collect::<Vec<_>>().join(", "),
            })?;
        let sequences = method
            .get("sequences")
            .and_then(Value::as_object)
            .ok_or_else(|| not_results("the method has no `sequences` object"))?;
        for (name, entry) in sequences {
            let score = entry
                .get("add_s")
                .and_then(Value::as_f64)
                .filter(|v| v.is_finite())
                .ok_or_else(|| PairingError::BadScore {
                    file: file.clone(),
                    sequence: name.clone(),
                })?;
            let motion = entry
                .get("motion")
                .and_then(Value::as_str)
                .unwrap_or("-")
                .to_string();
            let entry = scores
                .entry((suite.to_string(), name.clone()))
                .or_insert((motion, 0.0, 0));
            entry.1 += score;
            entry.2 += 1;
        }
    }
    Ok(scores)
}

fn listed(keys: &[&(String, String)]) -> String {
    let mut names: Vec<String> = keys
        .iter()
        .take(10)
        .map(|(s, q)| format!("{s}/{q}"))
        .collect();
    if keys.len() > 10 {
        names.push(format!("and {} more", keys.len() - 10));
    }
    if names.is_empty() {
        "none".to_string()
    } else {
        names.join(", ")
    }
}

/// Pairs the sequences of the base runs with those of the candidate runs by suite and sequence name; where a side
/// has several runs of a suite (twins: the same parameters nudged), a sequence's score there is their mean. Every
/// sequence must be in both: a comparison over different sequences says nothing about the change.
pub fn pair_results(
    base: &RunSide<'_>,
    candidate: &RunSide<'_>,
) -> Result<Vec<PairedScore>, PairingError> {
    let b = side_scores(base, "base")?;
    let c = side_scores(candidate, "candidate")?;
    let only_base: Vec<_> = b.keys().filter(|k| !c.contains_key(*k)).collect();
    let only_candidate: Vec<_> = c.keys().filter(|k| !b.contains_key(*k)).collect();
    if !only_base.is_empty() || !only_candidate.is_empty() {
        return Err(PairingError::Unpaired {
            only_base: listed(&only_base),
            only_candidate: listed(&only_candidate),
        });
    }
    Ok(b.into_iter()
        .map(|((suite, sequence), (motion, base_sum, base_runs))| {
            let (_, candidate_sum, candidate_runs) = c[&(suite.clone(), sequence.clone())];
            PairedScore {
                suite,
                sequence,
                motion,
                base: base_sum / base_runs as f64,
                candidate: candidate_sum / candidate_runs as f64,
                base_runs,
                candidate_runs,
            }
        })
        .collect())
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

/// The comparison as Markdown: all sequences, then per suite and per motion profile, then the sequences that
/// moved most each way (at most `movers` each).
pub fn comparison_markdown(
    pairs: &[PairedScore],
    options: &PairedOptions,
    movers: usize,
) -> String {
    let mut rows: Vec<PairedSummary> = Vec::new();
    let all: Vec<&PairedScore> = pairs.iter().collect();
    rows.extend(summarise_pairs("all", &all, options));
    let mut suites: BTreeMap<&str, Vec<&PairedScore>> = BTreeMap::new();
    let mut motions: BTreeMap<&str, Vec<&PairedScore>> = BTreeMap::new();
    for p in pairs {
        suites.entry(&p.suite).or_default().push(p);
        motions.entry(&p.motion).or_default().push(p);
    }
    if suites.len() > 1 {
        for (suite, set) in &suites {
            rows.extend(summarise_pairs(&format!("suite {suite}"), set, options));
        }
    }
    for (motion, set) in &motions {
        rows.extend(summarise_pairs(&format!("motion {motion}"), set, options));
    }
    let runs = |f: fn(&PairedScore) -> usize| {
        let lo = pairs.iter().map(f).min().unwrap_or(0);
        let hi = pairs.iter().map(f).max().unwrap_or(0);
        if lo == hi {
            format!("{lo}")
        } else {
            format!("{lo} to {hi}")
        }
    };
    let mut s = format!(
        "# Paired comparison\n\nADD-S AUC per sequence (120 Hz, percent), mean over sequences; a side's score of a sequence \
         is the mean of its runs of it (base: {} runs, candidate: {}). Difference = candidate - base, \
         with its 95 % bootstrap interval ({} resamples of the sequences, seed {}). Raised / lowered: sequences moved by \
         more than {} points. A difference whose interval spans 0 is within what the draw of sequences explains. Judge a change \
         on the first row: the rows below it are smaller sets, and among several of them one may exclude 0 by chance. \
         Against a single run of tuned defaults every change looks worse (they were kept for their luck): give each side \
         twins, runs with a parameter nudged by 1 %.\n\n\
         | set | sequences | base | candidate | difference | 95 % interval | beyond chance | raised | lowered |\n\
         | --- | ---: | ---: | ---: | ---: | --- | --- | ---: | ---: |\n",
        runs(|p| p.base_runs),
        runs(|p| p.candidate_runs),
        options.resamples.max(1),
        options.seed,
        options.moved
    );
    for r in &rows {
        s.push_str(&format!(
            "| {} | {} | {:.1} | {:.1} | {:+.1} | {:+.1} to {:+.1} | {} | {} | {} |\n",
            r.label,
            r.pairs,
            r.base_mean,
            r.candidate_mean,
            r.mean_difference,
            r.interval.0,
            r.interval.1,
            if r.is_beyond_chance() { "yes" } else { "no" },
            r.raised,
            r.lowered
        ));
    }
    let mut sorted: Vec<&PairedScore> = pairs.iter().collect();
    sorted.sort_by(|a, b| b.difference().total_cmp(&a.difference()));
    let mut list = |title: &str, items: Vec<&&PairedScore>| {
        s.push_str(&format!("\n## {title}\n\n"));
        if items.is_empty() {
            s.push_str("none\n");
        }
        for p in items {
            s.push_str(&format!(
                "- {}/{}: {:.1} -> {:.1} ({:+.1})\n",
                p.suite,
                p.sequence,
                p.base,
                p.candidate,
                p.difference()
            ));
        }
    };
    let up: Vec<_> = sorted
        .iter()
        .filter(|p| p.difference() > 0.0)
        .take(movers)
        .collect();
    let down: Vec<_> = sorted
        .iter()
        .rev()
        .filter(|p| p.difference() < 0.0)
        .take(movers)
        .collect();
    list("Raised most", up);
    list("Lowered most", down);
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use serde_json::json;

    fn run(suite: &str, method: &str, scores: &[(&str, f64)]) -> Value {
        let sequences: serde_json::Map<String, Value> = scores
            .iter()
            .map(|(name, s)| (name.to_string(), json!({"add_s": s, "motion": "shake"})))
            .collect();
        json!({"suite": suite, "methods": {method: {"sequences": sequences}}})
    }

    fn side<'a>(runs: &'a [(String, Value)]) -> RunSide<'a> {
        RunSide {
            runs,
            method: "eventtrack6d",
        }
    }

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

    #[test]
    fn large_swings_both_ways_are_not_beyond_chance() {
        let b: Vec<(String, f64)> = (0..36).map(|i| (format!("q{i}"), 50.0)).collect();
        let c: Vec<(String, f64)> = (0..36)
            .map(|i| (format!("q{i}"), if i % 2 == 0 { 90.0 } else { 8.0 }))
            .collect();
        fn as_ref(v: &[(String, f64)]) -> Vec<(&str, f64)> {
            v.iter().map(|(n, s)| (n.as_str(), *s)).collect()
        }
        let base = [("a".to_string(), run("s", "eventtrack6d", &as_ref(&b)))];
        let cand = [("b".to_string(), run("s", "eventtrack6d", &as_ref(&c)))];
        let pairs = pair_results(&side(&base), &side(&cand)).unwrap();
        let all: Vec<_> = pairs.iter().collect();
        let s = summarise_pairs("all", &all, &PairedOptions::default()).unwrap();
        assert!((s.mean_difference + 1.0).abs() < 1e-9, "{s:?}");
        assert!(s.interval.0 < -5.0 && s.interval.1 > 5.0, "{s:?}");
        assert!(!s.is_beyond_chance());
        assert_eq!((s.raised, s.lowered), (18, 18));
        let md = comparison_markdown(&pairs, &PairedOptions::default(), 3);
        assert!(md.contains("| all | 36 | 50.0 | 49.0 | -1.0 |"), "{md}");
        assert!(md.contains("s/q0: 50.0 -> 90.0 (+40.0)"), "{md}");
    }

    #[test]
    fn twins_on_a_side_count_by_their_mean() {
        let base = [
            (
                "a".to_string(),
                run("s", "eventtrack6d", &[("x", 10.0), ("y", 50.0)]),
            ),
            (
                "a+".to_string(),
                run("s", "eventtrack6d", &[("x", 30.0), ("y", 50.0)]),
            ),
            (
                "a-".to_string(),
                run("s", "eventtrack6d", &[("x", 20.0), ("y", 80.0)]),
            ),
        ];
        let cand = [(
            "b".to_string(),
            run("s", "eventtrack6d", &[("x", 25.0), ("y", 60.0)]),
        )];
        let pairs = pair_results(&side(&base), &side(&cand)).unwrap();
        let got: Vec<_> = pairs
            .iter()
            .map(|p| {
                (
                    p.sequence.as_str(),
                    p.base,
                    p.candidate,
                    p.base_runs,
                    p.candidate_runs,
                )
            })
            .collect();
        assert_eq!(got, vec![("x", 20.0, 25.0, 3, 1), ("y", 60.0, 60.0, 3, 1)]);
        let md = comparison_markdown(&pairs, &PairedOptions::default(), 2);
        assert!(md.contains("(base: 3 runs, candidate: 1)"), "{md}");
        assert!(md.contains("| all | 2 | 40.0 | 42.5 | +2.5 |"), "{md}");
    }

    #[test]
    fn runs_of_several_suites_pair_by_suite_and_sequence() {
        let base = [
            ("a".to_string(), run("fast", "eventtrack6d", &[("x", 10.0)])),
            (
                "b".to_string(),
                run("check", "eventtrack6d", &[("x", 20.0)]),
            ),
        ];
        let cand = [
            ("c".to_string(), run("check", "new", &[("x", 30.0)])),
            ("d".to_string(), run("fast", "new", &[("x", 40.0)])),
        ];
        let cand_side = RunSide {
            runs: &cand,
            method: "new",
        };
        let pairs = pair_results(&side(&base), &cand_side).unwrap();
        let d: Vec<_> = pairs
            .iter()
            .map(|p| (p.suite.as_str(), p.difference()))
            .collect();
        assert_eq!(d, vec![("check", 10.0), ("fast", 30.0)]);
        let md = comparison_markdown(&pairs, &PairedOptions::default(), 5);
        assert!(
            md.contains("| suite fast | 1 |") && md.contains("| suite check | 1 |"),
            "{md}"
        );
    }

    #[test]
    fn mismatched_runs_are_errors_that_name_what_is_wrong() {
        let base = [(
            "a".to_string(),
            run("s", "eventtrack6d", &[("x", 1.0), ("y", 2.0)]),
        )];
        let cand = [(
            "b".to_string(),
            run("s", "eventtrack6d", &[("x", 1.0), ("w", 2.0)]),
        )];
        let e = pair_results(&side(&base), &side(&cand)).unwrap_err();
        assert_eq!(
            e.to_string(),
            "the runs do not hold the same sequences: only in base: s/y; only in candidate: s/w"
        );
        let other = RunSide {
            runs: &cand,
            method: "depth30",
        };
        let e = pair_results(&side(&base), &other).unwrap_err();
        assert!(
            e.to_string()
                .contains("no method `depth30` (it has: eventtrack6d)"),
            "{e}"
        );
        let twice = [base[0].clone(), base[0].clone()];
        let e = pair_results(&side(&twice), &side(&cand)).unwrap_err();
        assert_eq!(e.to_string(), "a is given twice as base");
        let bad = [(
            "c".to_string(),
            json!({"suite": "s", "methods": {"eventtrack6d": {"sequences": {"x": {"add_s": "high"}}}}}),
        )];
        let e = pair_results(&side(&bad), &side(&cand)).unwrap_err();
        assert_eq!(e.to_string(), "c: sequence `x` has no finite add_s");
        let e = pair_results(&side(&[("d".to_string(), json!([1, 2]))]), &side(&cand)).unwrap_err();
        assert_eq!(
            e.to_string(),
            "d: not a bench results.json (no `suite` string)"
        );
    }

    fn arbitrary_json() -> impl Strategy<Value = Value> {
        let leaf = prop_oneof![
            Just(Value::Null),
            any::<bool>().prop_map(Value::from),
            (-1e3f64..1e3).prop_map(Value::from),
            "[a-z_]{0,8}".prop_map(Value::from),
        ];
        leaf.prop_recursive(4, 32, 6, |inner| {
            prop_oneof![
                proptest::collection::vec(inner.clone(), 0..4).prop_map(Value::from),
                proptest::collection::btree_map(
                    prop_oneof![
                        Just("suite".to_string()),
                        Just("methods".to_string()),
                        Just("eventtrack6d".to_string()),
                        Just("sequences".to_string()),
                        Just("add_s".to_string()),
                        "[a-z]{1,3}"
                    ],
                    inner,
                    0..4
                )
                .prop_map(|m| Value::Object(m.into_iter().collect())),
            ]
        })
    }

    proptest! {
        /// Any JSON on either side pairs or gives an error; it never panics.
        #[test]
        fn any_document_pairs_or_is_refused(a in arbitrary_json(), b in arbitrary_json()) {
            let base = [("a".to_string(), a)];
            let cand = [("b".to_string(), b)];
            if let Ok(pairs) = pair_results(&side(&base), &side(&cand)) {
                let md = comparison_markdown(&pairs, &PairedOptions { resamples: 20, ..PairedOptions::default() }, 2);
                prop_assert!(md.starts_with("# Paired comparison"));
            }
        }

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

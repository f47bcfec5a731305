//! Pairing two sets of bench runs: each side's `results.json` documents read into per-sequence scores (the mean
//! of a side's runs of a sequence) and matched by suite and sequence name.

use super::score::PairedScore;
use serde_json::Value;
use std::collections::BTreeMap;

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::paired::report::comparison_markdown;
    use crate::paired::summary::PairedOptions;
    use crate::paired::test_runs::{run, side};
    use proptest::prelude::*;
    use serde_json::json;

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
        assert!(
            md.contains("(runs per sequence: base 3, candidate 1)"),
            "{md}"
        );
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
    }
}

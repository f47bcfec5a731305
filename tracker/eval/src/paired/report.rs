//! The comparison as Markdown: the summary rows, then the sequences that moved most.

use super::score::PairedScore;
use super::summary::{PairedOptions, PairedSummary, summarise_pairs};
use std::collections::BTreeMap;

/// The comparison as Markdown: all sequences, then per suite and per motion profile, then the sequences that
/// moved most each way (at most `movers` each).
pub fn comparison_markdown(
    pairs: &[PairedScore],
    options: &PairedOptions,
    movers: usize,
) -> String {
    let mut s = header(pairs, options);
    for r in &summary_rows(pairs, options) {
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
    s.push_str(&movers_markdown(pairs, movers));
    s
}

/// The summary of all pairs, then of each suite (when there are several), then of each motion profile.
fn summary_rows(pairs: &[PairedScore], options: &PairedOptions) -> Vec<PairedSummary> {
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
    rows
}

/// The title, what the table says, and the table's head.
fn header(pairs: &[PairedScore], options: &PairedOptions) -> String {
    let runs = |f: fn(&PairedScore) -> usize| {
        let lo = pairs.iter().map(f).min().unwrap_or(0);
        let hi = pairs.iter().map(f).max().unwrap_or(0);
        if lo == hi {
            format!("{lo}")
        } else {
            format!("{lo} to {hi}")
        }
    };
    format!(
        "# Paired comparison\n\nADD-S AUC per sequence (120 Hz, percent), mean over sequences; a side's score of a sequence \
         is the mean of its runs of it (runs per sequence: base {}, candidate {}). Difference = candidate - base, \
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
    )
}

/// The sequences the candidate raised most and lowered most, at most `movers` each.
fn movers_markdown(pairs: &[PairedScore], movers: usize) -> String {
    let mut s = String::new();
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
    use crate::paired::pairing::pair_results;
    use crate::paired::test_runs::{run, side};

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
}

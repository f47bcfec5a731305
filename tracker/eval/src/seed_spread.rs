//! How much a method's scores depend on chance: the same perturbed first pose (`NAME@DEG:CM`) drawn with several
//! seeds (`bench --seeds N`), and per seed the mean ADD-S, the failures and the slow / moderate sequences that
//! raised `lost`. One run of a suite cannot tell a change's effect from the tracker's sensitivity to its start;
//! the spread over seeds can.

use super::bench::results::MethodResults;
use super::quality_report::{method_quality_report, sequence_label};
use super::recall::AucLimit;
use serde::Serialize;
use std::collections::BTreeMap;

/// Splits a method's report name into its seed group and seed: `eventtrack6d@1,0.2,s3` is seed 3 of
/// `eventtrack6d@1,0.2`; a name without a `,sSEED` suffix is seed 1 of itself.
pub fn seed_group(name: &str) -> (&str, u64) {
    if let Some((group, seed)) = name.rsplit_once(",s")
        && group.contains('@')
        && let Ok(seed) = seed.parse::<u64>()
    {
        return (group, seed);
    }
    (name, 1)
}

/// One method at one seed.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SeedRun {
    /// Seed of the first-pose perturbation.
    pub seed: u64,
    /// Object-mean ADD-S AUC at 120 Hz, percent.
    pub add_s: f64,
    /// Sequences that truly failed ([`super::quality_report::QualityReport::failed`]).
    pub failed: usize,
    /// Failed sequences that never raised `lost`.
    pub silent_failures: usize,
    /// Slow and moderate sequences (or `sequence/object`) that raised `lost` at least once, in suite order.
    pub lost_slow_moderate: Vec<String>,
}

/// A seed group: the runs of one method and first-pose error at two or more seeds, in seed order.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SeedSpread {
    /// The method's name without the seed (`eventtrack6d@1,0.2`).
    pub group: String,
    /// One entry per seed.
    pub runs: Vec<SeedRun>,
}

impl SeedSpread {
    /// Mean, lowest and highest of the runs' mean ADD-S (percent).
    pub fn add_s_range(&self) -> (f64, f64, f64) {
        let n = self.runs.len().max(1) as f64;
        let mean = self.runs.iter().map(|r| r.add_s).sum::<f64>() / n;
        let lo = self
            .runs
            .iter()
            .map(|r| r.add_s)
            .fold(f64::INFINITY, f64::min);
        let hi = self
            .runs
            .iter()
            .map(|r| r.add_s)
            .fold(f64::NEG_INFINITY, f64::max);
        (mean, lo, hi)
    }

    /// Every slow / moderate sequence that raised `lost` at some seed, with at how many seeds, in first-seen
    /// order.
    pub fn lost_counts(&self) -> Vec<(String, usize)> {
        let mut out: Vec<(String, usize)> = Vec::new();
        for name in self.runs.iter().flat_map(|r| &r.lost_slow_moderate) {
            match out.iter_mut().find(|(n, _)| n == name) {
                Some((_, k)) => *k += 1,
                None => out.push((name.clone(), 1)),
            }
        }
        out
    }
}

/// The seed groups of `results` with at least two members, in order of their first member.
pub fn seed_spreads(results: &[MethodResults], limit: AucLimit) -> Vec<SeedSpread> {
    let mut groups: BTreeMap<&str, (usize, Vec<SeedRun>)> = BTreeMap::new();
    for (i, m) in results.iter().enumerate() {
        let (group, seed) = seed_group(&m.name);
        let quality = method_quality_report(m);
        let run = SeedRun {
            seed,
            add_s: m.mean(false, limit).add_s,
            failed: quality.failed,
            silent_failures: quality.silent_failures.len(),
            lost_slow_moderate: lost_slow_moderate(m),
        };
        groups.entry(group).or_insert((i, Vec::new())).1.push(run);
    }
    let mut out: Vec<(usize, SeedSpread)> = groups
        .into_iter()
        .filter(|(_, (_, runs))| runs.len() >= 2)
        .map(|(group, (first, mut runs))| {
            runs.sort_by_key(|r| r.seed);
            (
                first,
                SeedSpread {
                    group: group.to_string(),
                    runs,
                },
            )
        })
        .collect();
    out.sort_by_key(|(first, _)| *first);
    out.into_iter().map(|(_, s)| s).collect()
}

/// Slow and moderate sequences of `m` that raised `lost` at least once (`sequence/object` where a sequence has
/// several objects).
fn lost_slow_moderate(m: &MethodResults) -> Vec<String> {
    m.sequences
        .iter()
        .filter(|s| {
            matches!(s.sequence.speed.as_str(), "slow" | "moderate")
                && s.records.iter().any(|r| r.state == "lost")
        })
        .map(|s| sequence_label(m, s))
        .collect()
}

/// The `results.md` section of the seed groups (empty without any).
pub fn seed_spread_markdown(spreads: &[SeedSpread]) -> String {
    use std::fmt::Write as _;
    if spreads.is_empty() {
        return String::new();
    }
    let mut s = String::from(
        "\n## Spread over first-pose seeds (120 Hz)\n\nThe same first-pose error drawn with each seed (random \
         axis and direction). Per seed, in seed order: failed sequences, of them without `lost`, and slow / \
         moderate sequences that raised `lost`.\n\n| method | seeds | ADD-S mean (lowest - highest) | per seed | \
         failed | failed without `lost` | slow / moderate with `lost` |\n| --- | ---: | ---: | --- | --- | --- | \
         --- |\n",
    );
    for g in spreads {
        let (mean, lo, hi) = g.add_s_range();
        let join =
            |f: &dyn Fn(&SeedRun) -> String| g.runs.iter().map(f).collect::<Vec<_>>().join(", ");
        let _ = writeln!(
            s,
            "| {} | {} | {mean:.1} ({lo:.1} - {hi:.1}) | {} | {} | {} | {} |",
            g.group,
            g.runs.len(),
            join(&|r| format!("{:.1}", r.add_s)),
            join(&|r| r.failed.to_string()),
            join(&|r| r.silent_failures.to_string()),
            join(&|r| r.lost_slow_moderate.len().to_string()),
        );
    }
    s.push('\n');
    for g in spreads {
        let counts = g.lost_counts();
        let names = if counts.is_empty() {
            "none".to_string()
        } else {
            counts
                .iter()
                .map(|(n, k)| format!("{n} ({k} of {})", g.runs.len()))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let _ = writeln!(
            s,
            "- {}: slow / moderate sequences with `lost`: {names}.",
            g.group
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seed_groups_read_back_the_report_names() {
        assert_eq!(
            seed_group("eventtrack6d@1,0.2,s3"),
            ("eventtrack6d@1,0.2", 3)
        );
        assert_eq!(seed_group("eventtrack6d@1,0.2"), ("eventtrack6d@1,0.2", 1));
        assert_eq!(seed_group("eventtrack6d"), ("eventtrack6d", 1));
        // A suffix that is not a seed, or a name without a first-pose error, stays whole.
        assert_eq!(
            seed_group("eventtrack6d@1,0.2,sx"),
            ("eventtrack6d@1,0.2,sx", 1)
        );
        assert_eq!(seed_group("gt-noise,s2"), ("gt-noise,s2", 1));
    }

    #[test]
    fn spread_and_lost_counts() {
        let run = |seed, add_s, lost: &[&str]| SeedRun {
            seed,
            add_s,
            failed: 1,
            silent_failures: 0,
            lost_slow_moderate: lost.iter().map(|s| s.to_string()).collect(),
        };
        let g = SeedSpread {
            group: "eventtrack6d@1,0.2".into(),
            runs: vec![
                run(1, 60.0, &["a-moderate"]),
                run(2, 64.0, &[]),
                run(3, 59.0, &["b-slow", "a-moderate"]),
            ],
        };
        let (mean, lo, hi) = g.add_s_range();
        assert!((mean - 61.0).abs() < 1e-9 && lo == 59.0 && hi == 64.0);
        assert_eq!(
            g.lost_counts(),
            vec![("a-moderate".to_string(), 2), ("b-slow".to_string(), 1)]
        );
        let md = seed_spread_markdown(&[g]);
        assert!(
            md.contains("| eventtrack6d@1,0.2 | 3 | 61.0 (59.0 - 64.0) | 60.0, 64.0, 59.0 |"),
            "{md}"
        );
        assert!(md.contains("a-moderate (2 of 3), b-slow (1 of 3)"), "{md}");
        assert!(seed_spread_markdown(&[]).is_empty());
    }
}

//! Fixed, named suites of sequences for benchmarking (every library object under several motion profiles and
//! speed levels, and objects of shapes the library lacks), generated once and reused.

use crate::generate::{
    Companion, GenerateConfig, GenerateError, GenerateReport, ObjectSource, generate,
};
use crate::motion::{MotionProfile, SpeedLevel};
use crate::objects::ObjectKind;
use crate::objects::novel::{NovelFamily, novel_name};
use drivers::recording::Recording;
use serde_json::json;
use std::path::{Path, PathBuf};

/// One sequence of a suite.
#[derive(Debug, Clone, PartialEq)]
pub struct SuiteEntry {
    /// Directory name inside the suite, e.g. `mug-shake-fast`.
    pub name: String,
    /// What to generate.
    pub config: GenerateConfig,
    /// The part of the suite it belongs to, where results are reported by part (`fast`: `dev-like`,
    /// `holdout-like`, `novel`); written into `suite.json`.
    pub group: Option<&'static str>,
}

/// Names of the suites [`suite`] knows.
pub const SUITES: [&str; 6] = ["dev", "holdout", "smoke", "multi", "fast", "fast-check"];

/// Seeds of the `fast` suite: its dev-like library round, holdout-like library round and novel objects start here
/// (dev uses 1000 on, holdout 3000 on).
const FAST_SEEDS: [u64; 3] = [5000, 6000, 7000];

/// Seeds of the `fast-check` suite, the same three groups as `fast` on seeds no other suite uses.
const FAST_CHECK_SEEDS: [u64; 3] = [8000, 9000, 10000];

/// Novel objects in the `fast` suite (each family twice).
const FAST_NOVEL: usize = 12;

/// The sequences of a named suite: `dev` is every library object under three profiles (one slow, one
/// moderate, one fast; the six profiles rotate across objects so each appears six times), 3 s each; `holdout`
/// has the shape of `dev` with other seeds and the profiles rotated on by three, so every object meets other
/// motion-speed pairs (for checking a change tuned on `dev` on recordings it was not tuned on); `smoke`
/// is two objects, 1 s each, for quick end-to-end checks; `multi` is 12 scenes of two objects each (the second
/// on its own trajectory 15 cm nearer the camera, so they hide each other), every library object in one to three scenes, 2-3 s.
/// `fast` is 36 sequences of 3 s, all at fast speed: two rounds of the 12 library objects (group `dev-like`, seeds
/// 5000-5011, object `i` under profile `i`, as dev pairs it at slow speed; group `holdout-like`, seeds 6000-6011,
/// profile `i + 3`, as holdout pairs it at slow speed; neither the profile dev nor holdout give it at fast speed),
/// then 12 novel objects (group `novel`, `novel:7000` to `novel:7011`, each shape family twice under two profiles,
/// each profile twice), for checking fast motion on seeds and shapes nothing was tuned on.
pub fn suite(name: &str) -> Option<Vec<SuiteEntry>> {
    let entry = library_entry;
    match name {
        "dev" | "holdout" => {
            let (rotate, first_seed) = if name == "dev" { (0, 1000) } else { (3, 3000) };
            let mut out = Vec::new();
            for (i, kind) in ObjectKind::ALL.into_iter().enumerate() {
                for (j, speed) in SpeedLevel::ALL.into_iter().enumerate() {
                    let motion =
                        MotionProfile::ALL[(i + 2 * j + rotate) % MotionProfile::ALL.len()];
                    let seed = first_seed + (i * 3 + j) as u64;
                    out.push(entry(kind, motion, speed, 3.0, seed));
                }
            }
            Some(out)
        }
        "smoke" => Some(vec![
            entry(
                ObjectKind::Can,
                MotionProfile::Shake,
                SpeedLevel::Moderate,
                1.0,
                1,
            ),
            entry(
                ObjectKind::Mug,
                MotionProfile::Translation,
                SpeedLevel::Slow,
                1.0,
                2,
            ),
        ]),
        "multi" => {
            use MotionProfile::{DepthVariation, HandSwitch, Rotation, Shake, Translation};
            use ObjectKind::*;
            use SpeedLevel::{Moderate, Slow};
            // (first object, its motion and speed, second object, its motion and speed, seconds, seed)
            let scenes = [
                (Mug, Translation, Slow, Can, HandSwitch, Moderate, 3.0, 4),
                (
                    CrackerBox,
                    Rotation,
                    Slow,
                    Bottle,
                    Translation,
                    Moderate,
                    3.0,
                    6,
                ),
                (Bowl, Shake, Slow, Banana, HandSwitch, Slow, 3.0, 7),
                (Drill, Translation, Moderate, Mug, Shake, Moderate, 2.0, 14),
                (
                    PuddingBox, Shake, Moderate, Marker, HandSwitch, Moderate, 2.0, 15,
                ),
                (
                    Spatula,
                    Rotation,
                    Moderate,
                    CrackerBox,
                    Translation,
                    Slow,
                    2.0,
                    16,
                ),
                (
                    Hammer,
                    Translation,
                    Slow,
                    Bowl,
                    HandSwitch,
                    Moderate,
                    2.0,
                    17,
                ),
                (
                    Can,
                    DepthVariation,
                    Moderate,
                    WineGlass,
                    Translation,
                    Slow,
                    2.0,
                    18,
                ),
                (
                    Bottle, Shake, Moderate, PuddingBox, Rotation, Moderate, 2.0, 19,
                ),
                (
                    Banana,
                    Translation,
                    Moderate,
                    Drill,
                    HandSwitch,
                    Slow,
                    2.0,
                    20,
                ),
                (
                    WineGlass,
                    Rotation,
                    Slow,
                    Can,
                    Translation,
                    Moderate,
                    2.0,
                    21,
                ),
                (Marker, Translation, Slow, Spatula, Shake, Moderate, 2.0, 22),
            ];
            let out = scenes
                .into_iter()
                .map(|(a, am, asp, b, bm, bsp, seconds, seed)| {
                    let mut e = entry(a, am, asp, seconds, seed);
                    e.name = format!("{}+{}-{}-{}", e.name, b.name(), bm.name(), bsp.name());
                    e.config.companions.push(Companion {
                        object: ObjectSource::Library(b),
                        motion: bm,
                        speed: bsp,
                        offset_m: Companion::default_offset(1),
                    });
                    e
                })
                .collect();
            Some(out)
        }
        "fast" => Some(fast_suite(FAST_SEEDS, [0, 3], 0)),
        "fast-check" => Some(fast_suite(FAST_CHECK_SEEDS, [2, 5], 1)),
        _ => None,
    }
}

/// The sequence `<object>-<motion>-<speed>` of library object `kind`, in no group.
fn library_entry(
    kind: ObjectKind,
    motion: MotionProfile,
    speed: SpeedLevel,
    seconds: f64,
    seed: u64,
) -> SuiteEntry {
    SuiteEntry {
        name: format!("{}-{}-{}", kind.name(), motion.name(), speed.name()),
        config: GenerateConfig::new(ObjectSource::Library(kind), motion, speed, seconds, seed),
        group: None,
    }
}

/// A fast-motion suite of 36 sequences of 3 s: the 12 library objects twice (groups `dev-like` on seeds from
/// `seeds[0]`, object `i` under profile `i + turns[0]`, and `holdout-like` on seeds from `seeds[1]` under profile
/// `i + turns[1]`), then 12 novel objects on seeds from `seeds[2]` (group `novel`, each family twice under two
/// profiles two apart, turned on by `novel_turn`).
fn fast_suite(seeds: [u64; 3], turns: [usize; 2], novel_turn: usize) -> Vec<SuiteEntry> {
    let speed = SpeedLevel::Fast;
    let n = MotionProfile::ALL.len();
    let mut out = Vec::new();
    for (group, rotate, first_seed) in [
        ("dev-like", turns[0], seeds[0]),
        ("holdout-like", turns[1], seeds[1]),
    ] {
        for (i, kind) in ObjectKind::ALL.into_iter().enumerate() {
            let motion = MotionProfile::ALL[(i + rotate) % n];
            out.push(SuiteEntry {
                group: Some(group),
                ..library_entry(kind, motion, speed, 3.0, first_seed + i as u64)
            });
        }
    }
    for k in 0..FAST_NOVEL {
        let seed = seeds[2] + k as u64;
        let family = NovelFamily::for_seed(seed);
        // The second round turns each family's profile on by two.
        let motion = MotionProfile::ALL[(k + 2 * (k / n) + novel_turn) % n];
        out.push(SuiteEntry {
            name: format!(
                "{}-{}-{}",
                novel_name(family, seed),
                motion.name(),
                speed.name()
            ),
            config: GenerateConfig::new(
                ObjectSource::Novel { family, seed },
                motion,
                speed,
                3.0,
                seed,
            ),
            group: Some("novel"),
        });
    }
    out
}

/// Whether `dir` already holds a complete recording generated from `config` by this generator version.
fn up_to_date(dir: &Path, config: &GenerateConfig) -> bool {
    let Ok(rec) = Recording::open(dir) else {
        return false;
    };
    let p = &rec.meta.parameters;
    rec.meta.generator == format!("hil-sim {}", env!("CARGO_PKG_VERSION"))
        && config
            .object
            .object_name()
            .is_none_or(|name| p.get("object") == Some(&json!(name)))
        && p.get("motion") == Some(&json!(config.motion.name()))
        && p.get("speed") == Some(&json!(config.speed.name()))
        && p.get("seconds") == Some(&json!(config.seconds))
        && p.get("seed") == Some(&json!(config.seed))
        && p.get("companions")
            .and_then(|c| c.as_array())
            .map_or(0, Vec::len)
            == config.companions.len()
}

/// Generates (or reuses) every sequence of `entries` under `out` on up to `jobs` threads (each sequence is
/// generated whole by one thread, from its own seed, so the recordings do not depend on `jobs`), and writes
/// `out/suite.json` listing them. `on_sequence(index, entry, report)` is called as each one finishes (`report`
/// is `None` when reused), in the order they finish; `progress(index, simulated_s)` reports how far the
/// sequence `index` has got. After the first failure no further sequence is started, and that error is returned.
pub fn generate_suite(
    name: &str,
    entries: &[SuiteEntry],
    out: &Path,
    jobs: usize,
    mut on_sequence: impl FnMut(usize, &SuiteEntry, Option<&GenerateReport>) + Send,
    progress: impl Fn(usize, f64) + Sync,
) -> Result<Vec<PathBuf>, GenerateError> {
    let dirs: Vec<PathBuf> = entries.iter().map(|e| out.join(&e.name)).collect();
    for_each_parallel(
        entries.len(),
        jobs,
        |i| {
            let (e, dir) = (&entries[i], &dirs[i]);
            if up_to_date(dir, &e.config) {
                Ok(None)
            } else {
                generate(&e.config, dir, |t| progress(i, t)).map(Some)
            }
        },
        |i, report| on_sequence(i, &entries[i], report.as_ref()),
    )?;
    let path = out.join("suite.json");
    let text = serde_json::to_string_pretty(&suite_index(name, entries)).unwrap_or_default();
    std::fs::write(&path, text).map_err(|error| GenerateError::Io { path, error })?;
    Ok(dirs)
}

/// The content of `suite.json`: the suite's name and, per sequence, its directory name, object, motion, speed,
/// length, seed and (where the suite has parts) group.
fn suite_index(name: &str, entries: &[SuiteEntry]) -> serde_json::Value {
    let list: Vec<_> = entries
        .iter()
        .map(|e| {
            let object = match &e.config.object {
                ObjectSource::File(p) => p.display().to_string(),
                o => o.object_name().unwrap_or_default(),
            };
            let mut entry = json!({"name": e.name, "object": object, "motion": e.config.motion.name(),
                   "speed": e.config.speed.name(), "seconds": e.config.seconds, "seed": e.config.seed});
            if let (Some(group), Some(map)) = (e.group, entry.as_object_mut()) {
                map.insert("group".into(), json!(group));
            }
            entry
        })
        .collect();
    json!({"suite": name, "sequences": list})
}

/// Runs `work(i)` for every `i` in `0..n` on up to `jobs` threads (at least one), taking indices in order, and
/// hands each result to `done(i, result)` on the thread that produced it, one call at a time. Once a `work` call
/// fails no further index is started; the error of the lowest failed index is returned.
fn for_each_parallel<T, E: Send>(
    n: usize,
    jobs: usize,
    work: impl Fn(usize) -> Result<T, E> + Sync,
    done: impl FnMut(usize, T) + Send,
) -> Result<(), E> {
    use std::sync::Mutex;
    use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
    let next = AtomicUsize::new(0);
    let failed = AtomicBool::new(false);
    let done = Mutex::new(done);
    let errors: Mutex<Vec<(usize, E)>> = Mutex::new(Vec::new());
    let worker = || {
        while !failed.load(Ordering::SeqCst) {
            let i = next.fetch_add(1, Ordering::SeqCst);
            if i >= n {
                break;
            }
            match work(i) {
                Ok(v) => {
                    let mut done = done.lock().unwrap_or_else(|p| p.into_inner());
                    (*done)(i, v);
                }
                Err(e) => {
                    failed.store(true, Ordering::SeqCst);
                    errors
                        .lock()
                        .unwrap_or_else(|p| p.into_inner())
                        .push((i, e));
                }
            }
        }
    };
    std::thread::scope(|scope| {
        for _ in 1..jobs.clamp(1, n.max(1)) {
            scope.spawn(worker);
        }
        worker();
    });
    let mut errors = errors.into_inner().unwrap_or_else(|p| p.into_inner());
    errors.sort_by_key(|(i, _)| *i);
    match errors.into_iter().next() {
        Some((_, e)) => Err(e),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dev_and_holdout_suites_cover_every_object_profile_and_speed() {
        for name in ["dev", "holdout"] {
            check_covers_every_object_profile_and_speed(&suite(name).unwrap());
        }
        assert!(suite("nope").is_none());
    }

    #[test]
    fn holdout_suite_shares_no_seed_and_gives_objects_other_profiles_than_dev() {
        let (dev, holdout) = (suite("dev").unwrap(), suite("holdout").unwrap());
        for h in &holdout {
            assert!(
                dev.iter().all(|d| d.config.seed != h.config.seed),
                "{}",
                h.name
            );
            let same = dev
                .iter()
                .find(|d| d.config.object == h.config.object && d.config.speed == h.config.speed);
            assert_ne!(
                same.map(|d| d.config.motion),
                Some(h.config.motion),
                "{}",
                h.name
            );
        }
    }

    fn check_covers_every_object_profile_and_speed(s: &[SuiteEntry]) {
        assert_eq!(s.len(), ObjectKind::ALL.len() * 3);
        for kind in ObjectKind::ALL {
            let n = s
                .iter()
                .filter(|e| e.config.object == ObjectSource::Library(kind))
                .count();
            assert_eq!(n, 3, "{kind:?}");
        }
        for p in MotionProfile::ALL {
            assert_eq!(s.iter().filter(|e| e.config.motion == p).count(), 6, "{p}");
        }
        for sp in SpeedLevel::ALL {
            assert_eq!(
                s.iter().filter(|e| e.config.speed == sp).count(),
                12,
                "{sp}"
            );
        }
        let mut names: Vec<_> = s.iter().map(|e| &e.name).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), s.len());
    }

    #[test]
    fn fast_suite_is_fast_library_and_novel_objects_on_new_seeds_and_pairings() {
        fast_suite_checks(&suite("fast").unwrap(), &[]);
    }

    #[test]
    fn fast_check_suite_is_a_fast_suite_on_seeds_and_objects_no_other_suite_has() {
        let fast = suite("fast").unwrap();
        let check = suite("fast-check").unwrap();
        fast_suite_checks(&check, &fast);
        // Its novel objects are other shapes than `fast`'s (their seeds make the shape).
        let novel_names = |s: &[SuiteEntry]| -> Vec<String> {
            s.iter()
                .filter(|e| e.group == Some("novel"))
                .map(|e| e.config.object.object_name().unwrap())
                .collect()
        };
        let fast_novel = novel_names(&fast);
        assert!(novel_names(&check).iter().all(|n| !fast_novel.contains(n)));
        // And its library objects meet other profiles than in `fast`.
        for e in check.iter().filter(|e| e.group != Some("novel")) {
            let same = fast
                .iter()
                .find(|f| f.group == e.group && f.config.object == e.config.object)
                .unwrap();
            assert_ne!(same.config.motion, e.config.motion, "{}", e.name);
        }
    }

    /// The checks every fast suite passes; `others` are further suites whose seeds it must not reuse.
    fn fast_suite_checks(fast: &[SuiteEntry], others: &[SuiteEntry]) {
        let (dev, holdout) = (suite("dev").unwrap(), suite("holdout").unwrap());
        assert!(fast.len() >= 36, "{}", fast.len());
        let mut names: Vec<_> = fast.iter().map(|e| &e.name).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), fast.len(), "directory names differ");
        let mut seeds: Vec<_> = fast.iter().map(|e| e.config.seed).collect();
        seeds.sort_unstable();
        seeds.dedup();
        assert_eq!(seeds.len(), fast.len(), "seeds differ");
        for e in fast {
            assert_eq!(e.config.speed, SpeedLevel::Fast, "{}", e.name);
            assert_eq!(e.config.seconds, 3.0, "{}", e.name);
            assert!(e.config.companions.is_empty(), "{}", e.name);
            assert!(
                dev.iter()
                    .chain(&holdout)
                    .chain(others)
                    .all(|d| d.config.seed != e.config.seed),
                "{}: seed used by another suite",
                e.name
            );
            let novel = matches!(e.config.object, ObjectSource::Novel { .. });
            assert_eq!(e.name.starts_with("novel_"), novel, "{}", e.name);
            assert_eq!(e.group == Some("novel"), novel, "{}", e.name);
            assert!(e.name.starts_with(&e.config.object.object_name().unwrap()));
        }
        for p in MotionProfile::ALL {
            let n = fast.iter().filter(|e| e.config.motion == p).count();
            assert!(n >= 4, "{p}: {n}");
        }
        // Library: every object in the dev-like and in the holdout-like round, each time under a profile that
        // neither dev nor holdout gives it at fast speed.
        for kind in ObjectKind::ALL {
            let lib = ObjectSource::Library(kind);
            let mine: Vec<_> = fast.iter().filter(|e| e.config.object == lib).collect();
            let groups: Vec<_> = mine.iter().map(|e| e.group).collect();
            assert_eq!(groups, [Some("dev-like"), Some("holdout-like")], "{kind:?}");
            assert_ne!(mine[0].config.motion, mine[1].config.motion, "{kind:?}");
            for e in &mine {
                for other in dev.iter().chain(&holdout) {
                    if other.config.object == lib && other.config.speed == SpeedLevel::Fast {
                        assert_ne!(other.config.motion, e.config.motion, "{}", e.name);
                    }
                }
            }
        }
        // Novel objects: at least 12, every family at least twice under two profiles, every profile.
        let novel: Vec<_> = fast
            .iter()
            .filter_map(|e| match e.config.object {
                ObjectSource::Novel { family, seed } => Some((family, seed, e.config.motion)),
                _ => None,
            })
            .collect();
        assert!(novel.len() >= 12);
        for family in NovelFamily::ALL {
            let mut profiles: Vec<_> = novel
                .iter()
                .filter(|n| n.0 == family)
                .map(|n| n.2)
                .collect();
            assert!(profiles.len() >= 2, "{family:?}");
            profiles.dedup();
            assert!(profiles.len() >= 2, "{family:?} under one profile");
        }
        for p in MotionProfile::ALL {
            assert!(novel.iter().any(|n| n.2 == p), "no novel object under {p}");
        }
    }

    #[test]
    fn suite_index_names_objects_and_groups() {
        let index = suite_index("fast", &suite("fast").unwrap());
        let seqs = index["sequences"].as_array().unwrap();
        assert_eq!(index["suite"], "fast");
        assert_eq!(seqs[0]["object"], "cracker_box");
        assert_eq!(seqs[0]["group"], "dev-like");
        let last = seqs.last().unwrap();
        assert_eq!(last["group"], "novel");
        assert!(last["object"].as_str().unwrap().starts_with("novel_"));
        assert!(
            last["name"]
                .as_str()
                .unwrap()
                .starts_with(last["object"].as_str().unwrap())
        );
        let dev = suite_index("dev", &suite("dev").unwrap());
        assert!(dev["sequences"][0].get("group").is_none());
    }

    #[test]
    fn multi_suite_has_two_distinct_objects_per_scene_and_every_library_object() {
        let s = suite("multi").unwrap();
        assert_eq!(s.len(), 12);
        for kind in ObjectKind::ALL {
            let lib = ObjectSource::Library(kind);
            let n = s
                .iter()
                .filter(|e| e.config.object == lib || e.config.companions[0].object == lib)
                .count();
            assert!((1..=3).contains(&n), "{kind:?} in {n} scenes");
        }
        for e in &s {
            assert_eq!(e.config.companions.len(), 1, "{}", e.name);
            assert_ne!(e.config.object, e.config.companions[0].object, "{}", e.name);
        }
    }

    #[test]
    fn parallel_runs_do_every_index_once_whatever_the_thread_count() {
        for jobs in [0, 1, 2, 5, 64] {
            let mut seen = Vec::new();
            for_each_parallel(
                17,
                jobs,
                |i| Ok::<_, ()>(i * i),
                |i, v| {
                    assert_eq!(v, i * i);
                    seen.push(i);
                },
            )
            .unwrap();
            seen.sort_unstable();
            assert_eq!(seen, (0..17).collect::<Vec<_>>(), "jobs {jobs}");
        }
        let mut calls = 0;
        for_each_parallel(0, 4, |_| Ok::<_, ()>(()), |_, _| calls += 1).unwrap();
        assert_eq!(calls, 0);
    }

    #[test]
    fn parallel_runs_stop_starting_work_after_a_failure_and_return_it() {
        use std::sync::atomic::{AtomicUsize, Ordering};
        for jobs in [1, 3] {
            let started = AtomicUsize::new(0);
            let r = for_each_parallel(
                100,
                jobs,
                |i| {
                    started.fetch_add(1, Ordering::SeqCst);
                    if i == 4 {
                        return Err(format!("index {i}"));
                    }
                    std::thread::sleep(std::time::Duration::from_millis(5));
                    Ok(())
                },
                |_, _| {},
            );
            assert_eq!(r, Err("index 4".to_string()), "jobs {jobs}");
            let started = started.load(Ordering::SeqCst);
            if jobs == 1 {
                assert_eq!(started, 5);
            } else {
                assert!(started < 100, "jobs {jobs}: all {started} started");
            }
        }
    }
}

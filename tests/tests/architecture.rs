//! The workspace's architecture holds: no cycles between source files, and every crate depends only on the crates
//! it may (`tools/architecture.py`, docs/architecture.md). And the check would see a cycle if there were one.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn check(args: &[&str]) -> Output {
    Command::new("python3")
        .arg(workspace().join("tools/architecture.py"))
        .args(args)
        .output()
        .expect("python3 runs tools/architecture.py")
}

#[test]
fn no_file_cycles_and_crates_depend_the_allowed_way() {
    let out = check(&[]);
    let report = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{report}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(report.contains("cycles: 0"), "{report}");
    // The whole workspace was read, not an empty tree.
    let files: usize = report
        .split("files: ")
        .nth(1)
        .and_then(|r| r.split(',').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or(0);
    assert!(files > 150, "{report}");
}

#[test]
fn a_cycle_and_an_impl_away_from_its_type_are_reported() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("src");
    std::fs::create_dir_all(&src).unwrap();
    std::fs::write(src.join("lib.rs"), "mod a;\nmod b;\nmod c;\nmod d;\n").unwrap();
    // a and b use each other's items.
    std::fs::write(
        src.join("a.rs"),
        "use crate::b::Two;\npub struct One(pub Two);\n",
    )
    .unwrap();
    std::fs::write(
        src.join("b.rs"),
        "pub struct Two;\npub fn f(_: &crate::a::One) {}\n",
    )
    .unwrap();
    // d implements c's type: c's users call into d, and d needs c.
    std::fs::write(src.join("c.rs"), "pub struct Three;\n").unwrap();
    std::fs::write(
        src.join("d.rs"),
        "use super::c::Three;\nimpl Three {\n    pub fn go(&self) {}\n}\n",
    )
    .unwrap();
    let root = format!("demo={}", src.join("lib.rs").display());
    let out = check(&[&root]);
    let report = String::from_utf8_lossy(&out.stdout);
    assert!(!out.status.success(), "{report}");
    assert!(report.contains("cycles: 2"), "{report}");
    assert!(report.contains("impl Three in"), "{report}");

    // Without the back edges there is none.
    std::fs::write(src.join("b.rs"), "pub struct Two;\n").unwrap();
    std::fs::write(
        src.join("c.rs"),
        "pub struct Three;\nimpl Three {\n    pub fn go(&self) {}\n}\n",
    )
    .unwrap();
    std::fs::write(
        src.join("d.rs"),
        "use super::c::Three;\npub fn go(t: &Three) { t.go() }\n",
    )
    .unwrap();
    let out = check(&[&root]);
    let report = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{report}");
    assert!(report.contains("cycles: 0"), "{report}");
}

//! `eventtrack6d eval` and `bench` refuse bad input with a clear error naming it, never a panic.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod cli;

use cli::fails_with;
use std::path::Path;

#[test]
fn eval_bad_inputs() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let missing = d.join("missing.csv");
    fails_with(
        &[
            "eval",
            "--pred",
            missing.to_str().unwrap(),
            "--gt",
            d.to_str().unwrap(),
        ],
        "cannot read predictions",
    );
    let bad = d.join("bad.csv");
    std::fs::write(&bad, "t,x\n").unwrap();
    fails_with(
        &[
            "eval",
            "--pred",
            bad.to_str().unwrap(),
            "--gt",
            d.to_str().unwrap(),
        ],
        "pose CSV line 1: expected header",
    );
    let bad_row = d.join("row.csv");
    std::fs::write(
        &bad_row,
        "t_us,object,x,y,z,qx,qy,qz,qw,quality,state\n0,can,0,0,nan,0,0,0,1,1,tracking\n",
    )
    .unwrap();
    fails_with(
        &[
            "eval",
            "--pred",
            bad_row.to_str().unwrap(),
            "--gt",
            d.to_str().unwrap(),
        ],
        "line 2: z `nan` is not a finite number",
    );
    let good = d.join("good.csv");
    std::fs::write(
        &good,
        "t_us,object,x,y,z,qx,qy,qz,qw,quality,state\n0,can,0,0,0.5,0,0,0,1,1,tracking\n",
    )
    .unwrap();
    let no_rec = d.join("no-recording");
    fails_with(
        &[
            "eval",
            "--pred",
            good.to_str().unwrap(),
            "--gt",
            no_rec.to_str().unwrap(),
        ],
        "no-recording",
    );
    // Revised estimates: a missing or malformed file is named before anything is scored.
    let revised = d.join("poses.revised.csv");
    fails_with(
        &[
            "eval",
            "--pred",
            good.to_str().unwrap(),
            "--revised",
            revised.to_str().unwrap(),
            "--gt",
            no_rec.to_str().unwrap(),
        ],
        "cannot read revised estimates",
    );
    std::fs::write(&revised, "t_us,object\n").unwrap();
    fails_with(
        &[
            "eval",
            "--pred",
            good.to_str().unwrap(),
            "--revised",
            revised.to_str().unwrap(),
            "--gt",
            no_rec.to_str().unwrap(),
        ],
        "poses.revised.csv",
    );
}

#[test]
fn bench_bad_inputs() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let out = out.to_str().unwrap();
    fails_with(
        &[
            "bench",
            "--suite",
            "smoke",
            "--methods",
            "static,magic",
            "--out",
            out,
        ],
        "unknown method `magic`",
    );
    fails_with(
        &[
            "bench",
            "--suite",
            "smoke",
            "--methods",
            "gt-noise:a:1",
            "--out",
            out,
        ],
        "translation noise (mm) `a`",
    );
    // --seeds repeats perturbed tracker methods only, and says so when there is none; a seed must be a number.
    fails_with(
        &[
            "bench",
            "--suite",
            "smoke",
            "--methods",
            "eventtrack6d,static",
            "--seeds",
            "3",
            "--out",
            out,
        ],
        "--methods has none",
    );
    fails_with(
        &[
            "bench",
            "--suite",
            "smoke",
            "--methods",
            "eventtrack6d",
            "--seeds",
            "0",
            "--out",
            out,
        ],
        "--seeds",
    );
    fails_with(
        &[
            "bench",
            "--suite",
            "smoke",
            "--methods",
            "eventtrack6d@1:1:x",
            "--out",
            out,
        ],
        "seed `x`",
    );
    // Tracker parameters are checked before any suite is generated or read.
    let params = dir.path().join("params.toml");
    std::fs::write(&params, "[redetect]\nplaces_per_tik = 1\n").unwrap();
    fails_with(
        &[
            "bench",
            "--suite",
            "smoke",
            "--methods",
            "eventtrack6d",
            "--out",
            out,
            "--params",
            params.to_str().unwrap(),
        ],
        "places_per_tik",
    );
    let nowhere = Path::new("does/not/exist");
    fails_with(
        &[
            "bench",
            "--suite",
            nowhere.to_str().unwrap(),
            "--methods",
            "static",
            "--out",
            out,
        ],
        "does not exist",
    );
    let empty = dir.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    fails_with(
        &[
            "bench",
            "--suite",
            empty.to_str().unwrap(),
            "--methods",
            "static",
            "--out",
            out,
        ],
        "no recordings",
    );
    let broken = dir.path().join("broken");
    std::fs::create_dir(&broken).unwrap();
    std::fs::write(
        broken.join("suite.json"),
        "{\"sequences\": [{\"name\": 3}]}",
    )
    .unwrap();
    fails_with(
        &[
            "bench",
            "--suite",
            broken.to_str().unwrap(),
            "--methods",
            "static",
            "--out",
            out,
        ],
        "sequences[0] has no string `name`",
    );
}

#[test]
fn track_bad_inputs() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let out = d.join("poses.csv");
    let out = out.to_str().unwrap();
    let rec = d.to_str().unwrap();
    fails_with(
        &["track", rec, "--out", out, "--method", "magic"],
        "unknown method `magic`",
    );
    fails_with(
        &["track", rec, "--out", out, "--init-noise", "5"],
        "expected DEG,CM",
    );
    fails_with(
        &["track", rec, "--out", out, "--init-noise", "x,5"],
        "degrees `x` is not a number",
    );
    let params = d.join("params.toml");
    std::fs::write(&params, "roi_sise = 128\n").unwrap();
    fails_with(
        &[
            "track",
            rec,
            "--out",
            out,
            "--params",
            params.to_str().unwrap(),
        ],
        "roi_sise",
    );
    // A known key out of range: named, with what it accepts.
    std::fs::write(&params, "[event_term]\nsigma_px = 0.0\n").unwrap();
    fails_with(
        &[
            "track",
            rec,
            "--out",
            out,
            "--params",
            params.to_str().unwrap(),
        ],
        "`event_term.sigma_px` = 0: must be a finite number > 0",
    );
    // Not a recording: the missing file is named.
    fails_with(&["track", rec, "--out", out], "camera.json: is missing");
}

//! The tracker's pose files: the output CSV `t_us,object,x,y,z,qx,qy,qz,qw,quality,state` that the CSV sink
//! writes and evaluation reads.

use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};
use std::fmt::Write as _;

/// Header line of the tracker output CSV.
pub const POSE_CSV_HEADER: &str = "t_us,object,x,y,z,qx,qy,qz,qw,quality,state";

/// One tracker output row: the pose of one object at one time.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseRecord {
    /// Time, microseconds on the event camera's clock.
    pub t_us: i64,
    /// Object name (as in the recording's `models_info.json`).
    pub object: String,
    /// `T_cam_obj` in the event camera frame, metres.
    pub pose: Isometry3<f64>,
    /// Tracking quality, unitless, 0 (lost) to 1 (confident).
    pub quality: f64,
    /// Tracker state name (e.g. `tracking`, `lost`).
    pub state: String,
}

/// Why a pose CSV could not be read; names the line.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("pose CSV line {line}: {reason}")]
pub struct PoseCsvError {
    /// 1-based line number.
    pub line: usize,
    /// What is wrong.
    pub reason: String,
}

/// The states a pose CSV row may carry (`tracker::track::TrackingState::as_str`).
pub const POSE_STATES: [&str; 3] = ["tracking", "degraded", "lost"];

/// Parses tracker output CSV text (header line required, blank lines ignored); rows keep file order. A row needs a
/// finite position, a unit quaternion (within 1e-3), a quality in [0, 1] and one of [`POSE_STATES`].
pub fn parse_pose_csv(text: &str) -> Result<Vec<PoseRecord>, PoseCsvError> {
    let mut lines = text.lines().enumerate();
    match lines.next() {
        Some((_, h)) if h.trim() == POSE_CSV_HEADER => {}
        Some((_, h)) => {
            return Err(PoseCsvError {
                line: 1,
                reason: format!("expected header `{POSE_CSV_HEADER}`, found `{}`", h.trim()),
            });
        }
        None => {
            return Err(PoseCsvError {
                line: 1,
                reason: "empty file (no header)".into(),
            });
        }
    }
    let mut out = Vec::new();
    for (i, raw) in lines {
        let line = i + 1;
        let raw = raw.trim();
        if raw.is_empty() {
            continue;
        }
        let err = |reason: String| PoseCsvError { line, reason };
        let f: Vec<&str> = raw.split(',').map(str::trim).collect();
        if f.len() != 11 {
            return Err(err(format!("expected 11 fields, found {}", f.len())));
        }
        let t_us: i64 = f[0]
            .parse()
            .map_err(|_| err(format!("t_us `{}` is not an integer", f[0])))?;
        if f[1].is_empty() {
            return Err(err("object name is empty".into()));
        }
        let mut v = [0.0f64; 8];
        let names = ["x", "y", "z", "qx", "qy", "qz", "qw", "quality"];
        for k in 0..8 {
            v[k] = f[k + 2]
                .parse()
                .ok()
                .filter(|x: &f64| x.is_finite())
                .ok_or_else(|| {
                    err(format!(
                        "{} `{}` is not a finite number",
                        names[k],
                        f[k + 2]
                    ))
                })?;
        }
        let q = Quaternion::new(v[6], v[3], v[4], v[5]);
        let norm = q.norm();
        if (norm - 1.0).abs() > 1e-3 {
            return Err(err(format!("quaternion norm {norm:.6} is not 1")));
        }
        if !(0.0..=1.0).contains(&v[7]) {
            return Err(err(format!("quality `{}` is not in [0, 1]", f[9])));
        }
        if !POSE_STATES.contains(&f[10]) {
            return Err(err(format!(
                "state `{}` is not one of {}",
                f[10],
                POSE_STATES.join(", ")
            )));
        }
        out.push(PoseRecord {
            t_us,
            object: f[1].to_string(),
            pose: Isometry3::from_parts(
                Translation3::new(v[0], v[1], v[2]),
                UnitQuaternion::from_quaternion(q),
            ),
            quality: v[7],
            state: f[10].to_string(),
        });
    }
    Ok(out)
}

/// Applies revised estimates (the runtime's `<name>.revised.csv`) to published ones: each published row whose
/// object and time a revised row has takes the last such revised row. Returns how many published rows changed
/// hands; revised rows of times not published are ignored.
pub fn apply_revisions(published: &mut [PoseRecord], revised: &[PoseRecord]) -> usize {
    let mut last = std::collections::HashMap::new();
    for r in revised {
        last.insert((r.object.as_str(), r.t_us), r);
    }
    let mut applied = 0;
    for p in published.iter_mut() {
        if let Some(r) = last.get(&(p.object.as_str(), p.t_us)) {
            *p = (*r).clone();
            applied += 1;
        }
    }
    applied
}

/// One row of the tracker output CSV, without its newline, as every writer of the format writes it: numbers in
/// Rust's shortest round-trip formatting, the quality as the tracker's `f32`.
#[derive(Debug, Clone, Copy)]
pub struct PoseRow<'a> {
    /// Time, microseconds on the event camera's clock.
    pub t_us: i64,
    /// Object name.
    pub object: &'a str,
    /// `T_cam_obj`, metres.
    pub pose: &'a Isometry3<f64>,
    /// Quality in [0, 1].
    pub quality: f32,
    /// `tracking`, `degraded` or `lost`.
    pub state: &'a str,
}

impl std::fmt::Display for PoseRow<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let t = self.pose.translation.vector;
        let q = self.pose.rotation.coords; // (i, j, k, w)
        write!(
            f,
            "{},{},{},{},{},{},{},{},{},{},{}",
            self.t_us, self.object, t.x, t.y, t.z, q.x, q.y, q.z, q.w, self.quality, self.state
        )
    }
}

/// Formats rows as tracker output CSV (with header), full precision.
pub fn format_pose_csv(records: &[PoseRecord]) -> String {
    let mut s = String::from(POSE_CSV_HEADER);
    s.push('\n');
    for r in records {
        let row = PoseRow {
            t_us: r.t_us,
            object: &r.object,
            pose: &r.pose,
            quality: r.quality as f32,
            state: &r.state,
        };
        let _ = writeln!(s, "{row}");
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;
    use proptest::prelude::*;

    fn sample() -> PoseRecord {
        PoseRecord {
            t_us: 8333,
            object: "can".into(),
            pose: Isometry3::new(Vector3::new(0.1, -0.2, 0.5), Vector3::new(0.0, 0.0, 0.3)),
            quality: 0.75,
            state: "tracking".into(),
        }
    }

    /// A pose CSV field as files may have it: a number, an extreme or non-finite one, text or nothing.
    fn field() -> impl Strategy<Value = String> {
        prop_oneof![
            4 => (-2.0f64..2.0).prop_map(|v| v.to_string()),
            2 => any::<i64>().prop_map(|v| v.to_string()),
            1 => Just("NaN".to_string()),
            1 => Just("-inf".to_string()),
            1 => Just("1e309".to_string()),
            1 => Just(String::new()),
            1 => "[a-z ]{1,6}",
        ]
    }

    proptest! {
        #[test]
        fn arbitrary_rows_parse_or_name_their_line(
            rows in prop::collection::vec(prop::collection::vec(field(), 0..13), 0..8),
            bytes in prop::collection::vec(any::<u8>(), 0..200),
        ) {
            let mut text = format!("{POSE_CSV_HEADER}\n");
            for r in &rows {
                text.push_str(&r.join(","));
                text.push('\n');
            }
            match parse_pose_csv(&text) {
                Ok(records) => {
                    prop_assert!(records.len() <= rows.len());
                    for r in &records {
                        prop_assert!(r.pose.translation.vector.iter().all(|v| v.is_finite()));
                        prop_assert!((r.pose.rotation.norm() - 1.0).abs() < 1e-9);
                        prop_assert!((0.0..=1.0).contains(&r.quality) && !r.object.is_empty());
                        prop_assert!(POSE_STATES.contains(&r.state.as_str()), "{}", r.state);
                    }
                }
                Err(e) => prop_assert!((2..=rows.len() + 1).contains(&e.line), "{}", e),
            }
            let text = String::from_utf8_lossy(&bytes);
            if let Err(e) = parse_pose_csv(&text) {
                prop_assert!((1..=text.lines().count().max(1)).contains(&e.line), "{}", e);
                prop_assert!(!e.reason.is_empty());
            }
        }

        #[test]
        fn written_rows_read_back(
            t_us in any::<i64>(),
            object in "[a-z_]{1,10}",
            t in prop::array::uniform3(-5.0f64..5.0),
            q in prop::array::uniform4(-1.0f64..1.0),
            quality in 0.0f32..=1.0,
            state in prop_oneof![Just("tracking"), Just("degraded"), Just("lost")],
        ) {
            let q = nalgebra::Quaternion::new(q[3], q[0], q[1], q[2]);
            prop_assume!(q.norm() > 1e-3);
            let record = PoseRecord {
                t_us,
                object,
                pose: Isometry3::from_parts(
                    Translation3::new(t[0], t[1], t[2]),
                    UnitQuaternion::from_quaternion(q),
                ),
                quality: f64::from(quality),
                state: state.to_string(),
            };
            let back = parse_pose_csv(&format_pose_csv(std::slice::from_ref(&record)))
                .map_err(|e| TestCaseError::fail(e.to_string()))?;
            prop_assert_eq!(back.len(), 1);
            let b = &back[0];
            prop_assert_eq!((b.t_us, &b.object, &b.state), (record.t_us, &record.object, &record.state));
            prop_assert_eq!(b.pose.translation, record.pose.translation);
            prop_assert!(b.pose.rotation.angle_to(&record.pose.rotation) < 1e-9);
            // The quality is written as the tracker's f32 (shortest form), so it reads back as that f32.
            prop_assert_eq!(b.quality as f32, quality);
        }
    }

    #[test]
    fn the_last_revision_of_a_tick_replaces_its_published_row() {
        let row = |t_us, object: &str, x: f64| PoseRecord {
            t_us,
            object: object.into(),
            pose: Isometry3::new(Vector3::new(x, 0.0, 0.5), Vector3::zeros()),
            quality: 0.5,
            state: "tracking".into(),
        };
        let mut published = vec![row(1, "can", 0.0), row(1, "mug", 0.0), row(2, "can", 0.0)];
        let revised = [
            row(1, "can", 0.1),
            row(1, "can", 0.2),
            row(3, "can", 0.3),
            row(2, "box", 0.4),
        ];
        assert_eq!(apply_revisions(&mut published, &revised), 1);
        assert_eq!(published[0].pose.translation.x, 0.2);
        assert_eq!(published[1].pose.translation.x, 0.0);
        assert_eq!(published[2].pose.translation.x, 0.0);
    }

    #[test]
    fn round_trip() {
        let rows = vec![sample()];
        let text = format_pose_csv(&rows);
        let back = parse_pose_csv(&text).unwrap();
        assert_eq!(back.len(), 1);
        assert_eq!(back[0].t_us, 8333);
        assert_eq!(back[0].state, "tracking");
        assert!(
            (back[0].pose.to_homogeneous() - rows[0].pose.to_homogeneous())
                .abs()
                .max()
                < 1e-12
        );
    }

    #[test]
    fn bad_rows_name_line_and_field() {
        let e = parse_pose_csv("t_us,object\n").unwrap_err();
        assert_eq!(e.line, 1);
        let e = parse_pose_csv(&format!("{POSE_CSV_HEADER}\n\n1,can,0,0,x,0,0,0,1,1,ok\n"))
            .unwrap_err();
        assert_eq!(e.line, 3);
        assert!(e.reason.contains("z `x`"), "{e}");
        let e =
            parse_pose_csv(&format!("{POSE_CSV_HEADER}\n1,can,0,0,1,0,0,0,2,1,ok\n")).unwrap_err();
        assert!(e.reason.contains("norm"), "{e}");
        let e = parse_pose_csv(&format!("{POSE_CSV_HEADER}\n1,can,0,0,1\n")).unwrap_err();
        assert!(e.reason.contains("11 fields"), "{e}");
        let e = parse_pose_csv(&format!(
            "{POSE_CSV_HEADER}\n1,can,0,0,1,0,0,0,1,0.5,tracking\n2,can,0,0,1,0,0,0,1,7,lost\n"
        ))
        .unwrap_err();
        assert_eq!(e.line, 3);
        assert!(e.reason.contains("quality `7`"), "{e}");
        let e = parse_pose_csv(&format!(
            "{POSE_CSV_HEADER}\n1,can,0,0,1,0,0,0,1,0.5,fine\n"
        ))
        .unwrap_err();
        assert!(e.reason.contains("state `fine`"), "{e}");
    }
}

//! Pose tables: `t_us,object,x,y,z,qx,qy,qz,qw` (ground truth at 120 Hz or denser).
//!
//! A pose is `T_cam_obj` in the event camera frame: translation in metres, unit quaternion (x, y, z, w).

use std::fmt::Write as _;

/// The header line of a ground-truth file.
pub const GROUND_TRUTH_HEADER: &str = "t_us,object,x,y,z,qx,qy,qz,qw";

/// One object pose at one time.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseSample {
    /// Time on the event camera's clock, microseconds.
    pub t_us: i64,
    /// Object name (a key of `models_info.json`).
    pub object: String,
    /// Translation of `T_cam_obj`, metres.
    pub translation: [f64; 3],
    /// Rotation of `T_cam_obj` as a unit quaternion `(x, y, z, w)`.
    pub rotation_xyzw: [f64; 4],
}

/// Parses a ground-truth table. Errors name the line and what is wrong. Per object, timestamps must not go
/// back; quaternions must be unit length within 1e-3 (they are renormalised).
pub fn parse_ground_truth(text: &str) -> Result<Vec<PoseSample>, String> {
    let mut out = Vec::new();
    let mut last: std::collections::HashMap<String, i64> = std::collections::HashMap::new();
    for (i, raw) in text.lines().enumerate() {
        let line_no = i + 1;
        let line = raw.trim();
        if line.is_empty() {
            continue;
        }
        if line_no == 1 {
            if line != GROUND_TRUTH_HEADER {
                return Err(format!(
                    "line 1: header is `{line}`, expected `{GROUND_TRUTH_HEADER}`"
                ));
            }
            continue;
        }
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        if f.len() != 9 {
            return Err(format!(
                "line {line_no}: {} fields, expected 9 ({GROUND_TRUTH_HEADER})",
                f.len()
            ));
        }
        let t_us: i64 = f[0]
            .parse()
            .map_err(|_| format!("line {line_no}: t_us `{}` is not an integer", f[0]))?;
        let mut v = [0.0f64; 7];
        for (k, name) in ["x", "y", "z", "qx", "qy", "qz", "qw"].iter().enumerate() {
            v[k] = f[2 + k]
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| {
                    format!(
                        "line {line_no}: {name} `{}` is not a finite number",
                        f[2 + k]
                    )
                })?;
        }
        let n = (v[3] * v[3] + v[4] * v[4] + v[5] * v[5] + v[6] * v[6]).sqrt();
        if (n - 1.0).abs() > 1e-3 {
            return Err(format!(
                "line {line_no}: quaternion norm is {n:.6}, expected 1"
            ));
        }
        let object = f[1].to_string();
        if object.is_empty() {
            return Err(format!("line {line_no}: object name is empty"));
        }
        if let Some(&prev) = last.get(&object)
            && t_us < prev
        {
            return Err(format!(
                "line {line_no}: timestamp {t_us} us of `{object}` goes back (previous {prev} us)"
            ));
        }
        last.insert(object.clone(), t_us);
        out.push(PoseSample {
            t_us,
            object,
            translation: [v[0], v[1], v[2]],
            rotation_xyzw: [v[3] / n, v[4] / n, v[5] / n, v[6] / n],
        });
    }
    Ok(out)
}

/// Formats poses as a ground-truth table with header. Numbers are written with enough digits to round-trip.
pub fn format_ground_truth(poses: &[PoseSample]) -> String {
    let mut s = String::with_capacity(64 * (poses.len() + 1));
    s.push_str(GROUND_TRUTH_HEADER);
    s.push('\n');
    for p in poses {
        let [x, y, z] = p.translation;
        let [qx, qy, qz, qw] = p.rotation_xyzw;
        let _ = writeln!(
            s,
            "{},{},{x:?},{y:?},{z:?},{qx:?},{qy:?},{qz:?},{qw:?}",
            p.t_us, p.object
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn roundtrip_and_errors() {
        let poses = vec![
            PoseSample {
                t_us: 0,
                object: "mug".into(),
                translation: [0.1, -0.2, 0.7],
                rotation_xyzw: [0.0, 0.0, 0.0, 1.0],
            },
            PoseSample {
                t_us: 8333,
                object: "mug".into(),
                translation: [0.1, -0.2, 0.7],
                rotation_xyzw: [0.6, 0.0, 0.0, 0.8],
            },
        ];
        assert_eq!(
            parse_ground_truth(&format_ground_truth(&poses)).unwrap(),
            poses
        );
        let back = format!("{GROUND_TRUTH_HEADER}\n10,a,0,0,1,0,0,0,1\n5,a,0,0,1,0,0,0,1\n");
        assert!(parse_ground_truth(&back).unwrap_err().contains("line 3"));
        let q = format!("{GROUND_TRUTH_HEADER}\n10,a,0,0,1,0,0,0,2\n");
        assert!(parse_ground_truth(&q).unwrap_err().contains("quaternion"));
        assert!(parse_ground_truth("t,x\n").unwrap_err().contains("header"));
    }
}

//! The BOP results CSV (`scene_id,im_id,obj_id,score,R,t,time`), the export the BOP toolkit scores.

use nalgebra::Isometry3;
use std::fmt::Write as _;

/// Header line of the BOP results CSV.
pub const BOP_CSV_HEADER: &str = "scene_id,im_id,obj_id,score,R,t,time";

/// One BOP results row: `scene_id` (sequence number), `im_id` (frame / tick index), `obj_id` (numeric object id),
/// `score` (the tracker quality) and the pose; `time_s` is the per-image run time in seconds (-1 when unknown).
#[derive(Debug, Clone, PartialEq)]
pub struct BopRow {
    /// Scene (sequence) number.
    pub scene_id: u32,
    /// Image (tick) number within the scene.
    pub im_id: u64,
    /// Numeric object id.
    pub obj_id: u32,
    /// Confidence score.
    pub score: f64,
    /// `T_cam_obj`, metres (written as R row-major and t in millimetres, as BOP).
    pub pose: Isometry3<f64>,
    /// Run time per image, seconds; -1 = unknown.
    pub time_s: f64,
}

/// Formats BOP results CSV text: R as 9 space-separated row-major numbers, t in millimetres.
pub fn format_bop_csv(rows: &[BopRow]) -> String {
    let mut s = String::from(BOP_CSV_HEADER);
    s.push('\n');
    for r in rows {
        let m = r.pose.rotation.to_rotation_matrix();
        let m = m.matrix();
        let rot: Vec<String> = (0..3)
            .flat_map(|i| (0..3).map(move |j| (i, j)))
            .map(|(i, j)| format!("{}", m[(i, j)]))
            .collect();
        let t = r.pose.translation.vector * 1000.0;
        let _ = writeln!(
            s,
            "{},{},{},{},{},{} {} {},{}",
            r.scene_id,
            r.im_id,
            r.obj_id,
            r.score,
            rot.join(" "),
            t.x,
            t.y,
            t.z,
            r.time_s
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    #[test]
    fn bop_row_hand_computed() {
        // 90 degrees about z: R = [[0,-1,0],[1,0,0],[0,0,1]]; t = (0.1, 0, 0.5) m -> (100, 0, 500) mm.
        let pose = Isometry3::new(
            Vector3::new(0.1, 0.0, 0.5),
            Vector3::new(0.0, 0.0, std::f64::consts::FRAC_PI_2),
        );
        let text = format_bop_csv(&[BopRow {
            scene_id: 2,
            im_id: 7,
            obj_id: 3,
            score: 0.5,
            pose,
            time_s: -1.0,
        }]);
        let line = text.lines().nth(1).unwrap();
        let f: Vec<&str> = line.split(',').collect();
        assert_eq!(&f[..4], &["2", "7", "3", "0.5"]);
        let r: Vec<f64> = f[4].split(' ').map(|v| v.parse().unwrap()).collect();
        let expect = [0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0];
        assert!(
            r.iter().zip(expect).all(|(a, b)| (a - b).abs() < 1e-12),
            "{r:?}"
        );
        let t: Vec<f64> = f[5].split(' ').map(|v| v.parse().unwrap()).collect();
        assert!((t[0] - 100.0).abs() < 1e-9 && t[1].abs() < 1e-9 && (t[2] - 500.0).abs() < 1e-9);
        assert_eq!(f[6], "-1");
    }
}

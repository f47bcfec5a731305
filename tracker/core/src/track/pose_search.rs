//! A coarse search over whole poses on one depth frame, for re-detection: the object's shape, as points sampled
//! on its surface, tried in many orientations at the places where it may be, each scored by how much of the
//! surface it shows the depth confirms. The best few become start poses for the full depth-only refinement of a
//! place check. A lost object is usually turned as well as moved, and a refinement started from its last
//! orientation converges near the hand or the wrong face.

use crate::recon::DepthRig;
use crate::track::foreground_map::ForegroundMap;
use crate::track::redetect::DepthBackground;
use drivers::recording::DepthFrame;
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use scene::mesh::SurfacePoint;

/// Points on an object's surface with their outward normals, object frame, metres.
#[derive(Debug, Clone, Default)]
pub(crate) struct ShapeSamples {
    points: Vec<(Point3<f64>, Vector3<f64>)>,
}

impl ShapeSamples {
    /// The samples `surface` (points on the mesh with their triangles' normals). A mesh wound inside out (its
    /// normals, weighted over the samples, point towards the box centre `centre_obj` rather than away) has every
    /// normal flipped; a consistently wound mesh keeps its own, concave parts included.
    pub fn new(surface: &[SurfacePoint], centre_obj: &Vector3<f64>) -> Self {
        let finite = |s: &&SurfacePoint| {
            s.position
                .coords
                .iter()
                .chain(s.normal.iter())
                .all(|v| v.is_finite())
        };
        let outward: f64 = surface
            .iter()
            .filter(finite)
            .map(|s| s.normal.dot(&(s.position.coords - centre_obj)))
            .sum();
        let sign = if outward < 0.0 { -1.0 } else { 1.0 };
        let points = surface
            .iter()
            .filter(finite)
            .map(|s| (s.position, s.normal * sign))
            .collect();
        Self { points }
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// The first `n` samples (all of them if there are fewer).
    pub fn prefix(&self, n: usize) -> Self {
        Self {
            points: self.points[..n.min(self.points.len())].to_vec(),
        }
    }
}

/// `views` orientations spread evenly over the sphere of directions the camera may see the object from (a
/// Fibonacci lattice), each with `rolls` turns about that direction: every orientation within about
/// `sqrt(4 pi / views)` radians of view and `pi / rolls` of roll of one of them.
pub(crate) fn orientation_lattice(views: usize, rolls: usize) -> Vec<UnitQuaternion<f64>> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let mut out = Vec::with_capacity(views * rolls);
    for i in 0..views {
        let z = 1.0 - (2.0 * i as f64 + 1.0) / views as f64;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = golden * i as f64;
        // The object direction that faces the camera (its -z axis in the camera frame).
        let facing = Vector3::new(r * phi.cos(), r * phi.sin(), z);
        let to_camera =
            UnitQuaternion::rotation_between(&facing, &-Vector3::z()).unwrap_or_else(|| {
                UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI)
            });
        for k in 0..rolls {
            let roll = UnitQuaternion::from_axis_angle(
                &Vector3::z_axis(),
                2.0 * std::f64::consts::PI * k as f64 / rolls as f64,
            );
            out.push(roll * to_camera);
        }
    }
    out
}

/// How a pose hypothesis is scored against a depth frame.
#[derive(Debug, Clone, Copy)]
pub(crate) struct HypothesisScoring {
    /// A surface point whose measured depth is within this of its own, metres, is confirmed.
    pub agree_m: f64,
    /// A measurement nearer than the point by more than this, metres, hides it (a hand in front): it counts neither way.
    pub occluder_m: f64,
    /// Residuals beyond this, metres, do not move the hypothesis along its line of sight.
    pub align_m: f64,
}

/// A scored pose hypothesis, `T_cam_obj` in the event camera frame.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Hypothesis {
    /// Confirmed minus contradicted surface samples, as a share of all samples: showing more of the surface where
    /// the depth has it scores higher, showing surface where the depth sees past it scores lower.
    pub score: f64,
    pub pose: Isometry3<f64>,
}

/// A depth frame and its camera, for scoring hypotheses.
pub(crate) struct DepthView<'a> {
    pub frame: &'a DepthFrame,
    pub rig: &'a DepthRig,
    /// Where the frame stands in front of the learned background: a surface point confirmed only by the
    /// background (a wall, the table) counts against a hypothesis, since the object is not part of it. `None`
    /// counts every measurement.
    pub background: Option<&'a DepthBackground>,
}

impl DepthView<'_> {
    /// The measured depth at the pixel `p` (depth camera frame) projects to, `None` outside the image or where
    /// nothing was measured,
    /// and whether it stands in front of the background.
    fn depth_at(&self, p: &Point3<f64>) -> Option<(f64, bool)> {
        let uv = self.rig.camera.project(p)?;
        let (u, v) = (uv.x.round(), uv.y.round());
        let (w, h) = (self.frame.width as f64, self.frame.height as f64);
        if !(u >= 0.0 && v >= 0.0 && u < w && v < h) {
            return None;
        }
        let (u, v) = (u as usize, v as usize);
        let d = *self.frame.depth_m.get(v * self.frame.width as usize + u)?;
        let front = self.background.is_none_or(|b| b.in_front(u, v));
        (d > 0.0 && d.is_finite()).then_some((f64::from(d), front))
    }

    /// `pose` (event camera frame) scored on this frame, after moving it along the depth camera's line of sight to
    /// its centre `centre_obj` by the median residual of its visible samples within `align_m` (where the
    /// measured surface says its near side is).
    pub fn score(
        &self,
        shape: &ShapeSamples,
        pose: &Isometry3<f64>,
        centre_obj: &Vector3<f64>,
        scoring: &HypothesisScoring,
        residuals: &mut Vec<f64>,
    ) -> Hypothesis {
        let depth_from_event = self.rig.event_from_depth.inverse();
        let in_depth = depth_from_event * pose;
        residuals.clear();
        for (p, n) in &shape.points {
            let q = in_depth * p;
            if (in_depth.rotation * n).dot(&q.coords) >= 0.0 {
                continue;
            }
            if let Some((d, true)) = self.depth_at(&q) {
                let r = d - q.z;
                if r.abs() <= scoring.align_m {
                    residuals.push(r);
                }
            }
        }
        let shift = if residuals.is_empty() {
            0.0
        } else {
            let mid = residuals.len() / 2;
            *residuals
                .select_nth_unstable_by(mid, |a, b| a.total_cmp(b))
                .1
        };
        let centre = in_depth * Point3::from(*centre_obj);
        let ray = centre.coords.normalize();
        let moved_depth = if ray.z > 1e-6 {
            Isometry3::from_parts(
                Translation3::from(ray * (shift / ray.z)),
                UnitQuaternion::identity(),
            ) * in_depth
        } else {
            in_depth
        };
        let (mut agree, mut contradict) = (0usize, 0usize);
        for (p, n) in &shape.points {
            let q = moved_depth * p;
            if (moved_depth.rotation * n).dot(&q.coords) >= 0.0 {
                continue;
            }
            let Some((d, front)) = self.depth_at(&q) else {
                continue;
            };
            let r = d - q.z;
            if r < -scoring.occluder_m {
                continue;
            }
            if front && r.abs() <= scoring.agree_m {
                agree += 1;
            } else {
                contradict += 1;
            }
        }
        let all = shape.len().max(1) as f64;
        Hypothesis {
            score: (agree as f64 - contradict as f64) / all,
            pose: self.rig.event_from_depth * moved_depth,
        }
    }
}

impl DepthView<'_> {
    /// `pose` (event camera frame) moved across the depth camera's line of sight so that its visible samples land
    /// on the foreground of `map`: by the mean way from the pixels of the samples off the foreground to their
    /// nearest foreground cells, at those samples' mean depth (samples on the foreground stay). A pose half on a
    /// thin object and half on the background beside it moves onto the object; a pose on the object with a few
    /// samples off its edges all round barely moves. `None` when no visible sample projects into the frame or the
    /// frame shows no foreground; `pose` itself when every visible sample is on the foreground.
    pub fn pull_sideways(
        &self,
        shape: &ShapeSamples,
        pose: &Isometry3<f64>,
        map: &ForegroundMap,
    ) -> Option<Isometry3<f64>> {
        let depth_from_event = self.rig.event_from_depth.inverse();
        let in_depth = depth_from_event * pose;
        let (mut du, mut dv, mut z, mut n, mut seen) = (0.0, 0.0, 0.0, 0usize, false);
        for (p, normal) in &shape.points {
            let q = in_depth * p;
            if (in_depth.rotation * normal).dot(&q.coords) >= 0.0 {
                continue;
            }
            let Some(uv) = self.rig.camera.project(&q) else {
                continue;
            };
            let Some((wu, wv)) = map.way_to_foreground(uv.x, uv.y) else {
                continue;
            };
            seen = true;
            if wu == 0.0 && wv == 0.0 {
                continue;
            }
            du += wu;
            dv += wv;
            z += q.z;
            n += 1;
        }
        if n == 0 {
            return seen.then_some(*pose);
        }
        let n = n as f64;
        let (du, dv, z) = (du / n, dv / n, z / n);
        let cam = &self.rig.camera;
        let shift = Vector3::new(du * z / cam.fx, dv * z / cam.fy, 0.0);
        if !shift.iter().all(|v| v.is_finite()) {
            return None;
        }
        let moved = Translation3::from(shift) * in_depth;
        Some(self.rig.event_from_depth * moved)
    }
}

/// Keeps the `k` best of `hypotheses` by score (best first) in `best`, dropping one within `min_apart` of a
/// better one: a place this close is where the refinement of the better one goes anyway.
pub(crate) fn keep_best(
    best: &mut Vec<Hypothesis>,
    candidate: Hypothesis,
    k: usize,
    centre_obj: &Vector3<f64>,
    min_apart: (f64, f64),
) {
    let near = |a: &Hypothesis, b: &Hypothesis| {
        let ca = a.pose * Point3::from(*centre_obj);
        let cb = b.pose * Point3::from(*centre_obj);
        (ca - cb).norm() < min_apart.0 && a.pose.rotation.angle_to(&b.pose.rotation) < min_apart.1
    };
    if let Some(i) = best.iter().position(|b| near(b, &candidate)) {
        if best[i].score >= candidate.score {
            return;
        }
        best.remove(i);
    }
    let at = best
        .iter()
        .position(|b| b.score < candidate.score)
        .unwrap_or(best.len());
    if at < k {
        best.insert(at, candidate);
        best.truncate(k);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use scene::geometry::PinholeCamera;

    /// The scoring of the tests: agreement within 1 cm, an occluder 2.5 cm nearer, alignment within 5 cm.
    const SCORING: HypothesisScoring = HypothesisScoring {
        agree_m: 0.01,
        occluder_m: 0.025,
        align_m: 0.05,
    };

    /// A box of half sizes `h` sampled on a grid of its faces, outward normals.
    fn box_samples(h: Vector3<f64>) -> ShapeSamples {
        let mut s = Vec::new();
        for axis in 0..3 {
            for sign in [-1.0, 1.0] {
                let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
                for i in 0..8 {
                    for j in 0..8 {
                        let mut p = Vector3::zeros();
                        p[axis] = sign * h[axis];
                        p[a] = h[a] * (2.0 * (i as f64 + 0.5) / 8.0 - 1.0);
                        p[b] = h[b] * (2.0 * (j as f64 + 0.5) / 8.0 - 1.0);
                        let mut n = Vector3::zeros();
                        n[axis] = sign;
                        // Inward on purpose: `new` flips a mesh wound inside out.
                        s.push(SurfacePoint {
                            position: Point3::from(p),
                            normal: -n,
                            triangle: 0,
                        });
                    }
                }
            }
        }
        ShapeSamples::new(&s, &Vector3::zeros())
    }

    /// A depth frame of the box `h` at `pose` (depth camera = event camera) in front of a wall at 1 m, by casting
    /// each pixel's ray against the box's faces.
    fn frame_of_box(cam: &PinholeCamera, h: Vector3<f64>, pose: &Isometry3<f64>) -> DepthFrame {
        let inv = pose.inverse();
        let mut depth_m = vec![1.0f32; (cam.width * cam.height) as usize];
        for v in 0..cam.height {
            for u in 0..cam.width {
                let dir = cam
                    .unproject(&nalgebra::Point2::new(u as f64, v as f64), 1.0)
                    .coords;
                let o = inv * Point3::origin();
                let d = inv.rotation * dir;
                // Slab intersection.
                let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
                for a in 0..3 {
                    let (lo, hi) = ((-h[a] - o[a]) / d[a], (h[a] - o[a]) / d[a]);
                    t0 = t0.max(lo.min(hi));
                    t1 = t1.min(lo.max(hi));
                }
                if t0 <= t1 && t0 > 0.0 && t0 < 1.0 {
                    depth_m[(v * cam.width + u) as usize] = t0 as f32;
                }
            }
        }
        DepthFrame {
            index: 0,
            width: cam.width,
            height: cam.height,
            depth_m,
        }
    }

    /// A 160 x 120 depth camera (300 px focal length) that is also the event camera, and the frame it takes of a
    /// box of half sizes `h` turned by the Euler angles `euler` at (0.01, -0.02, 0.6) m, in front of a wall at 1 m.
    fn box_scene(
        h: Vector3<f64>,
        euler: (f64, f64, f64),
    ) -> (DepthRig, Isometry3<f64>, DepthFrame) {
        let cam = PinholeCamera::new(300.0, 300.0, 79.5, 59.5, 160, 120).unwrap();
        let rig = DepthRig {
            camera: cam,
            event_from_depth: Isometry3::identity(),
        };
        let truth = Isometry3::from_parts(
            Translation3::new(0.01, -0.02, 0.6),
            UnitQuaternion::from_euler_angles(euler.0, euler.1, euler.2),
        );
        let frame = frame_of_box(&cam, h, &truth);
        (rig, truth, frame)
    }

    #[test]
    fn a_pose_beside_a_thin_object_is_pulled_onto_it() {
        // A marker-like stick, 16 mm thick, seen from 0.6 m in front of a wall at 1 m.
        let h = Vector3::new(0.06, 0.008, 0.008);
        let (rig, truth, frame) = box_scene(h, (0.2, 0.3, 0.4));
        let cam = rig.camera;
        let mut wall = frame.clone();
        wall.depth_m.fill(1.0);
        let mut background = DepthBackground::new(2, cam.width, cam.height);
        background.update(&wall);
        background.foreground(&frame, &rig, |_| 0.05, &mut Vec::new());
        let mut map = ForegroundMap::default();
        map.update(&background);
        let view = DepthView {
            frame: &frame,
            rig: &rig,
            background: Some(&background),
        };
        let shape = box_samples(h);
        let scoring = SCORING;
        let mut scratch = Vec::new();
        let c = Vector3::zeros();
        // 25 mm beside it, across the stick: none of its surface on the stick.
        let beside = Translation3::from(truth.rotation * Vector3::new(0.0, 0.025, 0.0)) * truth;
        let before = view.score(&shape, &beside, &c, &scoring, &mut scratch);
        let mut pulled = beside;
        for _ in 0..3 {
            pulled = view
                .pull_sideways(&shape, &pulled, &map)
                .expect("foreground");
            pulled = view.score(&shape, &pulled, &c, &scoring, &mut scratch).pose;
        }
        let after = view.score(&shape, &pulled, &c, &scoring, &mut scratch);
        let off = (pulled.translation.vector - truth.translation.vector).norm();
        assert!(off < 0.006, "still {off} m off");
        assert!(
            after.score > before.score + 0.2,
            "{} -> {}",
            before.score,
            after.score
        );
        // With nothing in front of the background there is nowhere to go.
        let mut empty = DepthBackground::new(2, cam.width, cam.height);
        empty.update(&wall);
        empty.foreground(&wall, &rig, |_| 0.05, &mut Vec::new());
        map.update(&empty);
        assert!(view.pull_sideways(&shape, &beside, &map).is_none());
    }

    #[test]
    fn the_lattice_covers_every_orientation() {
        let lattice = orientation_lattice(24, 6);
        assert_eq!(lattice.len(), 144);
        let mut rng = 17u64;
        let mut next = || {
            rng = rng
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (rng >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let mut worst = 0.0f64;
        for _ in 0..500 {
            let q = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
                next(),
                next(),
                next(),
                next(),
            ));
            let nearest = lattice
                .iter()
                .map(|l| l.angle_to(&q))
                .fold(f64::INFINITY, f64::min);
            worst = worst.max(nearest);
        }
        // 144 orientations: a random one lies within about 45 degrees of one of them.
        assert!(worst < 50f64.to_radians(), "{} degrees", worst.to_degrees());
    }

    #[test]
    fn the_true_pose_outscores_a_turned_or_moved_one_and_is_pulled_to_the_measured_range() {
        let h = Vector3::new(0.06, 0.03, 0.015);
        let (rig, truth, frame) = box_scene(h, (0.4, 0.3, 0.2));
        let view = DepthView {
            frame: &frame,
            rig: &rig,
            background: None,
        };
        let shape = box_samples(h);
        let scoring = SCORING;
        let mut scratch = Vec::new();
        let c = Vector3::zeros();
        let at_truth = view.score(&shape, &truth, &c, &scoring, &mut scratch);
        let turned = Isometry3::from_parts(
            truth.translation,
            UnitQuaternion::from_euler_angles(1.2, 0.3, 0.2),
        );
        let moved = Isometry3::from_parts(Translation3::new(0.05, -0.02, 0.6), truth.rotation);
        let behind = Isometry3::from_parts(Translation3::new(0.01, -0.02, 0.63), truth.rotation);
        let s_turned = view.score(&shape, &turned, &c, &scoring, &mut scratch);
        let s_moved = view.score(&shape, &moved, &c, &scoring, &mut scratch);
        let s_behind = view.score(&shape, &behind, &c, &scoring, &mut scratch);
        assert!(at_truth.score > 0.3, "{}", at_truth.score);
        assert!(
            s_turned.score < at_truth.score - 0.1,
            "{} vs {}",
            s_turned.score,
            at_truth.score
        );
        assert!(
            s_moved.score < at_truth.score - 0.1,
            "{} vs {}",
            s_moved.score,
            at_truth.score
        );
        // Three centimetres too far: moved back along the line of sight to within a few millimetres.
        let dz = (s_behind.pose.translation.vector - truth.translation.vector).norm();
        assert!(dz < 0.006, "{dz} m");
        assert!((s_behind.score - at_truth.score).abs() < 0.1);
    }

    proptest::proptest! {
        /// Any pose, finite or not, on any frame (its size possibly not matching its samples, any depths) scores
        /// within [-1, 1] without panicking, and a finite pose stays finite.
        #[test]
        fn any_pose_on_any_frame_scores_in_range(
            x in -1.0f64..1.0, y in -1.0f64..1.0, z in -2.0f64..2.0,
            ax in -4.0f64..4.0, ay in -4.0f64..4.0, az in -4.0f64..4.0,
            width in 0u32..24, height in 0u32..24, short in 0usize..3,
            depths in proptest::collection::vec(proptest::prop_oneof![
                proptest::strategy::Just(0.0f32),
                proptest::strategy::Just(f32::NAN),
                proptest::strategy::Just(f32::INFINITY),
                -1.0f32..3.0,
            ], 0..600),
            nan in proptest::bool::ANY,
        ) {
            let cam = PinholeCamera::new(20.0, 20.0, 10.0, 10.0, 24, 24).unwrap();
            let rig = DepthRig { camera: cam, event_from_depth: Isometry3::translation(0.01, 0.0, 0.0) };
            let len = (width * height) as usize;
            let mut depth_m: Vec<f32> = depths.iter().copied().cycle().take(len).collect();
            depth_m.truncate(len.saturating_sub(short));
            let frame = DepthFrame { index: 0, width, height, depth_m };
            let view = DepthView { frame: &frame, rig: &rig, background: None };
            let shape = box_samples(Vector3::new(0.05, 0.03, 0.02));
            let scoring = SCORING;
            let t = if nan { f64::NAN } else { x };
            let pose = Isometry3::from_parts(
                Translation3::new(t, y, z),
                UnitQuaternion::from_euler_angles(ax, ay, az),
            );
            let h = view.score(&shape, &pose, &Vector3::zeros(), &scoring, &mut Vec::new());
            proptest::prop_assert!((-1.0..=1.0).contains(&h.score), "{}", h.score);
            if !nan {
                proptest::prop_assert!(h.pose.translation.vector.iter().all(|v| v.is_finite()));
            }
        }
    }

    #[test]
    fn keep_best_holds_the_k_best_apart_in_order() {
        let at = |x: f64, score: f64| Hypothesis {
            score,
            pose: Isometry3::translation(x, 0.0, 0.6),
        };
        let c = Vector3::zeros();
        let apart = (0.01, 0.2);
        let mut best = Vec::new();
        for (x, s) in [(0.0, 0.2), (0.1, 0.5), (0.105, 0.6), (0.2, 0.1), (0.3, 0.4)] {
            keep_best(&mut best, at(x, s), 2, &c, apart);
        }
        let got: Vec<(f64, f64)> = best
            .iter()
            .map(|h| (h.pose.translation.x, h.score))
            .collect();
        assert_eq!(got, vec![(0.105, 0.6), (0.3, 0.4)]);
    }
}

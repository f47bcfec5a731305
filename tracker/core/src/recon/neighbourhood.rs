//! The depth around an object that moved between two depth frames, for checking the motion a pose hypothesis
//! implies. Whatever moves rigidly with the object (the hand holding it above all) moves by the same motion, so
//! the previous frame's moving surfaces, carried by the right motion, land on the new frame's surfaces; carried
//! by a motion that slid the object onto the hand, they land off them.

use super::{CarriedDepth, DepthRig, MAX_CARRIED_POINTS};
use drivers::recording::DepthFrame;
use nalgebra::{Isometry3, Matrix3, Point3, Vector3};
use scene::geometry::PinholeCamera;

/// Largest difference between a carried point's depth and the new frame's measurement for the frame to confirm
/// it, metres (the depth camera's noise at working distance is a few millimetres; a wrong motion moves surfaces
/// by centimetres).
pub const MOTION_TOLERANCE_M: f32 = 0.01;

/// Fewest scored points for a motion agreement to be reported.
pub const MIN_MOTION_POINTS: usize = 50;

/// The previous depth frame's points around one object that the new frame no longer measures where they were,
/// in the object frame at the previous frame's estimate (the anchor).
#[derive(Debug, Default)]
pub struct MovingNeighbourhood {
    /// Object frame at the anchor, metres.
    points: Vec<Point3<f32>>,
    /// `T_cam_obj` of the object at the previous frame.
    anchor: Isometry3<f64>,
}

impl Clone for MovingNeighbourhood {
    fn clone(&self) -> Self {
        Self {
            points: self.points.clone(),
            anchor: self.anchor,
        }
    }

    /// Reuses this neighbourhood's point buffer (no allocation once it is large enough).
    fn clone_from(&mut self, source: &Self) {
        self.points.clone_from(&source.points);
        self.anchor = source.anchor;
    }
}

impl MovingNeighbourhood {
    /// An empty neighbourhood, sized for the most points a carried depth keeps (no allocation later).
    pub fn new() -> Self {
        Self {
            points: Vec::with_capacity(MAX_CARRIED_POINTS),
            anchor: Isometry3::identity(),
        }
    }

    /// Points kept.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether no point is kept.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Forgets every point (no previous frame to compare with).
    pub fn clear(&mut self) {
        self.points.clear();
    }

    /// Takes the previous frame's points from `carried` (the depth carried since it, split at `anchor`, the
    /// object's pose then), then drops those that `frame` (the new depth frame) measures where they were: the
    /// static scene, and surfaces sliding within themselves, say nothing about the object's motion.
    pub fn capture(
        &mut self,
        carried: &CarriedDepth,
        anchor: &Isometry3<f64>,
        frame: &DepthFrame,
        rig: &DepthRig,
    ) {
        self.points.clear();
        self.anchor = *anchor;
        let from_event = Rigid::new(&rig.event_from_depth.inverse());
        let from_object = Rigid::new(&(rig.event_from_depth.inverse() * anchor));
        let to_object = Rigid::new(&anchor.inverse());
        let moved = |p: &Point3<f32>| {
            measured(frame, &rig.camera, p)
                .is_some_and(|z| !(z > 0.0 && (z - p.z).abs() < MOTION_TOLERANCE_M))
        };
        for p in carried.static_points() {
            if moved(&from_event.apply(p)) {
                self.points.push(to_object.apply(p));
            }
        }
        for q in carried.object_points() {
            if moved(&from_object.apply(q)) {
                self.points.push(*q);
            }
        }
    }

    /// How well `frame` confirms the motion from the anchor to `pose` (`T_cam_obj` at the new frame): the fraction
    /// of the kept points that land within [`MOTION_TOLERANCE_M`] of its measurement when carried by that motion,
    /// among those that land on a measurement not `occlusion_gap` metres or more in front of them (something
    /// nearer hides them). `None` below [`MIN_MOTION_POINTS`] such points.
    pub fn motion_agreement(
        &self,
        pose: &Isometry3<f64>,
        frame: &DepthFrame,
        rig: &DepthRig,
        occlusion_gap: f32,
    ) -> Option<f64> {
        let to_depth = Rigid::new(&(rig.event_from_depth.inverse() * pose));
        let (mut agree, mut scored) = (0usize, 0usize);
        for q in &self.points {
            let p = to_depth.apply(q);
            let Some(z) = measured(frame, &rig.camera, &p) else {
                continue;
            };
            if z <= 0.0 || z < p.z - occlusion_gap {
                continue;
            }
            scored += 1;
            if (z - p.z).abs() < MOTION_TOLERANCE_M {
                agree += 1;
            }
        }
        (scored >= MIN_MOTION_POINTS).then(|| agree as f64 / scored as f64)
    }

    /// The object's pose at the previous frame the points are kept relative to.
    pub fn anchor(&self) -> &Isometry3<f64> {
        &self.anchor
    }
}

/// A rigid transform as a rotation matrix and a translation in `f32` (cheaper per point than the quaternion).
struct Rigid {
    r: Matrix3<f32>,
    t: Vector3<f32>,
}

impl Rigid {
    fn new(iso: &Isometry3<f64>) -> Self {
        Self {
            r: iso.rotation.to_rotation_matrix().into_inner().cast::<f32>(),
            t: iso.translation.vector.cast::<f32>(),
        }
    }

    fn apply(&self, p: &Point3<f32>) -> Point3<f32> {
        Point3::from(self.r * p.coords + self.t)
    }
}

/// The frame's depth (metres, 0 where invalid) at the pixel `p` (depth camera frame) projects to; `None` when it
/// projects outside the image or the frame does not have the camera's size.
fn measured(frame: &DepthFrame, camera: &PinholeCamera, p: &Point3<f32>) -> Option<f32> {
    if frame.width != camera.width || frame.height != camera.height || p.z <= 0.01 {
        return None;
    }
    let u = (camera.fx as f32 * p.x / p.z + camera.cx as f32).round();
    let v = (camera.fy as f32 * p.y / p.z + camera.cy as f32).round();
    if !(u >= 0.0 && v >= 0.0 && u < camera.width as f32 && v < camera.height as f32) {
        return None;
    }
    frame
        .depth_m
        .get(v as usize * frame.width as usize + u as usize)
        .copied()
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point3 as P3;

    const W: usize = 200;
    const H: usize = 160;

    fn camera() -> PinholeCamera {
        PinholeCamera::new(200.0, 200.0, 99.5, 79.5, W as u32, H as u32).unwrap()
    }

    /// A wall at 2 m with a 80 x 60 pixel block (the object with its hand) at 0.6 m, its left edge at `u0`.
    fn frame(u0: usize) -> DepthFrame {
        let mut depth_m = vec![2.0f32; W * H];
        for v in 50..110 {
            for u in u0..u0 + 80 {
                depth_m[v * W + u] = 0.6;
            }
        }
        DepthFrame {
            index: 0,
            width: W as u32,
            height: H as u32,
            depth_m,
        }
    }

    /// The block moves 20 pixels (6 cm at 0.6 m) to the right between the frames.
    fn moved_block() -> (MovingNeighbourhood, DepthFrame, DepthRig, Isometry3<f64>) {
        let rig = DepthRig {
            camera: camera(),
            event_from_depth: Isometry3::identity(),
        };
        let before = frame(40);
        let anchor = Isometry3::translation(-0.06, 0.0, 0.6);
        let mut carried = CarriedDepth::new();
        carried.register(&before, &rig, &P3::new(-0.06, 0.0, 0.6), 0.3, 0);
        let after = frame(60);
        let mut n = MovingNeighbourhood::new();
        n.capture(&carried, &anchor, &after, &rig);
        let truth = Isometry3::translation(0.0, 0.0, 0.6);
        (n, after, rig, truth)
    }

    #[test]
    fn the_true_motion_is_confirmed_and_wrong_ones_are_not() {
        let (n, after, rig, truth) = moved_block();
        // What the new frame still measures in place (the block's overlap, the wall is out of range) is gone.
        assert!(!n.is_empty() && n.len() < 20 * 60, "{} points", n.len());
        let gap = 0.025;
        let right = n.motion_agreement(&truth, &after, &rig, gap).unwrap();
        assert!(right > 0.95, "true motion {right}");
        // Standing still, or 3 cm nearer the camera: the moved surfaces land on the wall or in front of the block.
        let still = n.motion_agreement(n.anchor(), &after, &rig, gap).unwrap();
        assert!(still < 0.05, "no motion {still}");
        let nearer = Isometry3::translation(0.0, 0.0, 0.57);
        let near = n.motion_agreement(&nearer, &after, &rig, gap).unwrap();
        assert!(near < 0.05, "3 cm nearer {near}");
    }

    #[test]
    fn too_few_points_or_a_mismatched_frame_give_no_agreement() {
        let (mut n, after, rig, truth) = moved_block();
        let small = DepthFrame {
            index: 0,
            width: 10,
            height: 10,
            depth_m: vec![0.6; 100],
        };
        assert_eq!(n.motion_agreement(&truth, &small, &rig, 0.025), None);
        // Far off to the side every point leaves the image.
        let away = Isometry3::translation(3.0, 0.0, 0.6);
        assert_eq!(n.motion_agreement(&away, &after, &rig, 0.025), None);
        n.clear();
        assert_eq!(n.motion_agreement(&truth, &after, &rig, 0.025), None);
    }
}

//! Depth reconstruction `D_t`: the last depth frame `D_0`, registered into the event camera by forward splatting
//! with a z-buffer, and carried to time `t` by the scene's motion field: points on the tracked object move with the
//! object's rigid motion since the exposure, everything else (background, occluders) stays where it was.

use drivers::recording::DepthFrame;
use nalgebra::{Isometry3, Point3, Vector3};
use scene::geometry::PinholeCamera;

/// The depth camera and where it sits relative to the event camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DepthRig {
    /// Depth camera intrinsics (pixels of the depth image).
    pub camera: PinholeCamera,
    /// `T_event_depth`: maps depth-camera points into the event camera frame, metres.
    pub event_from_depth: Isometry3<f64>,
}

/// A depth image in some (ROI) camera: `z` along the optical axis in metres, 0 = no measurement.
#[derive(Debug, Clone, Default)]
pub struct DepthImage {
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// Row-major depth, metres (0 = invalid).
    pub z: Vec<f32>,
}

impl DepthImage {
    /// Resizes to `width x height` and clears to invalid, reusing the buffer.
    pub fn reset(&mut self, width: u32, height: u32) {
        self.width = width;
        self.height = height;
        self.z.clear();
        self.z.resize(width as usize * height as usize, 0.0);
    }

    /// Depth at pixel `(u, v)` (pixel-centre integer coordinates), 0 outside or invalid.
    #[inline]
    pub fn at(&self, u: i32, v: i32) -> f32 {
        if u < 0 || v < 0 || u >= self.width as i32 || v >= self.height as i32 {
            return 0.0;
        }
        self.z[v as usize * self.width as usize + u as usize]
    }
}

/// One object's `D_0`: depth points around it at the last exposure, split into points that move with the object
/// (stored in the object frame at the exposure) and points that stay (stored in the event camera frame).
#[derive(Debug, Default)]
pub struct CarriedDepth {
    exposure_us: Option<i64>,
    static_points: Vec<Point3<f32>>,
    object_points: Vec<Point3<f32>>,
    /// Sampling stride in depth pixels of the last registration (sets the splat footprint).
    stride: u32,
    /// Horizontal focal length of the depth camera, pixels.
    depth_fx: f64,
}

impl Clone for CarriedDepth {
    fn clone(&self) -> Self {
        let mut c = Self::default();
        c.clone_from(self);
        c
    }

    /// Reuses this reconstruction's point buffers (no allocation once they are large enough).
    fn clone_from(&mut self, source: &Self) {
        self.exposure_us = source.exposure_us;
        self.static_points.clone_from(&source.static_points);
        self.object_points.clone_from(&source.object_points);
        self.stride = source.stride;
        self.depth_fx = source.depth_fx;
    }
}

/// Most depth points kept around one object per exposure (the depth image is subsampled above this).
pub const MAX_CARRIED_POINTS: usize = 12_000;

impl CarriedDepth {
    /// An empty reconstruction (no depth frame yet).
    pub fn new() -> Self {
        Self {
            static_points: Vec::with_capacity(MAX_CARRIED_POINTS),
            object_points: Vec::with_capacity(MAX_CARRIED_POINTS),
            ..Self::default()
        }
    }

    /// Time of the exposure `D_0` was taken at, microseconds; `None` before the first frame.
    pub fn exposure_us(&self) -> Option<i64> {
        self.exposure_us
    }

    /// Depth points kept (static + moving).
    pub fn len(&self) -> usize {
        self.static_points.len() + self.object_points.len()
    }

    /// Whether no depth point is kept.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Registers the part of `frame` around a sphere (`center`, event camera frame, `radius`, metres) as the new
    /// `D_0` exposed at `t_us`. Every point is static until [`Self::attach_to_object`] is called.
    pub fn register(
        &mut self,
        frame: &DepthFrame,
        rig: &DepthRig,
        center: &Point3<f64>,
        radius: f64,
        t_us: i64,
    ) {
        self.exposure_us = Some(t_us);
        self.static_points.clear();
        self.object_points.clear();
        let cam = &rig.camera;
        self.depth_fx = cam.fx;
        if frame.width != cam.width || frame.height != cam.height {
            self.stride = 1;
            return;
        }
        let c_d = rig.event_from_depth.inverse() * center;
        let near = (c_d.z - radius).max(0.05);
        let half_u = cam.fx * radius / near;
        let half_v = cam.fy * radius / near;
        let Some(c_px) = cam.project(&c_d) else {
            self.stride = 1;
            return;
        };
        let u0 = (c_px.x - half_u).floor().max(0.0) as i64;
        let u1 = (c_px.x + half_u).ceil().min(f64::from(cam.width) - 1.0) as i64;
        let v0 = (c_px.y - half_v).floor().max(0.0) as i64;
        let v1 = (c_px.y + half_v).ceil().min(f64::from(cam.height) - 1.0) as i64;
        if u1 < u0 || v1 < v0 {
            self.stride = 1;
            return;
        }
        let area = ((u1 - u0 + 1) * (v1 - v0 + 1)) as f64;
        let stride = (area / MAX_CARRIED_POINTS as f64).sqrt().ceil().max(1.0) as i64;
        self.stride = stride as u32;
        let iso = rig.event_from_depth.cast::<f32>();
        let (fx, fy, cx, cy) = (cam.fx as f32, cam.fy as f32, cam.cx as f32, cam.cy as f32);
        let (z_lo, z_hi) = ((c_d.z - radius) as f32, (c_d.z + radius) as f32);
        let w = frame.width as usize;
        let mut v = v0;
        while v <= v1 {
            let mut u = u0;
            while u <= u1 {
                let z = frame.depth_m[v as usize * w + u as usize];
                if z > 0.0
                    && z >= z_lo
                    && z <= z_hi
                    && self.static_points.len() < MAX_CARRIED_POINTS
                {
                    let p = Point3::new((u as f32 - cx) * z / fx, (v as f32 - cy) * z / fy, z);
                    self.static_points.push(iso * p);
                }
                u += stride;
            }
            v += stride;
        }
    }

    /// Splits `D_0` after the object's pose at the exposure is known: points inside the object's bounding box
    /// (`aabb_min`, `aabb_max`, object frame, enlarged by `margin` metres) at `pose_at_exposure` move with the
    /// object from now on; the rest stays.
    pub fn attach_to_object(
        &mut self,
        pose_at_exposure: &Isometry3<f64>,
        aabb_min: &Vector3<f64>,
        aabb_max: &Vector3<f64>,
        margin: f64,
    ) {
        let inv = pose_at_exposure.inverse().cast::<f32>();
        let lo = (aabb_min - Vector3::repeat(margin)).cast::<f32>();
        let hi = (aabb_max + Vector3::repeat(margin)).cast::<f32>();
        let mut i = 0;
        while i < self.static_points.len() {
            let x = inv * self.static_points[i];
            let inside = (0..3).all(|k| x[k] >= lo[k] && x[k] <= hi[k]);
            if inside {
                self.object_points.push(x);
                self.static_points.swap_remove(i);
            } else {
                i += 1;
            }
        }
    }

    /// For a `D_0` exposed before the tick it is used at: moves the points that lie in the object's box at
    /// `pose_at_exposure` (grown by `margin`, metres) by `motion` (event camera frame, applied on the left: the
    /// object's motion from the exposure to the tick). They stay among the static points, now where the object is
    /// estimated to be at the tick, until [`Self::attach_to_object`] splits them at the pose refined there.
    pub fn carry_object_part(
        &mut self,
        pose_at_exposure: &Isometry3<f64>,
        motion: &Isometry3<f64>,
        aabb_min: &Vector3<f64>,
        aabb_max: &Vector3<f64>,
        margin: f64,
    ) {
        let inv = pose_at_exposure.inverse().cast::<f32>();
        let motion = motion.cast::<f32>();
        let lo = (aabb_min - Vector3::repeat(margin)).cast::<f32>();
        let hi = (aabb_max + Vector3::repeat(margin)).cast::<f32>();
        for p in &mut self.static_points {
            let x = inv * *p;
            if (0..3).all(|k| x[k] >= lo[k] && x[k] <= hi[k]) {
                *p = motion * *p;
            }
        }
    }

    /// The points of `D_0` that stay where they were, event camera frame, metres.
    pub fn static_points(&self) -> &[Point3<f32>] {
        &self.static_points
    }

    /// The points of `D_0` that move with the object, object frame at the exposure (the pose
    /// [`Self::attach_to_object`] split them with), metres.
    pub fn object_points(&self) -> &[Point3<f32>] {
        &self.object_points
    }

    /// Renders `D_t` into `out` for the (ROI) camera `camera`: static points where they were, object points moved
    /// to `object_pose` (the object's pose at `t`). Nearest surface wins (z-buffer); each point covers a square
    /// footprint sized to the density of the depth samples.
    pub fn render(
        &self,
        object_pose: &Isometry3<f64>,
        camera: &PinholeCamera,
        out: &mut DepthImage,
    ) {
        out.reset(camera.width, camera.height);
        if self.is_empty() {
            return;
        }
        let ratio = camera.fx / (self.depth_fx / f64::from(self.stride.max(1)));
        let footprint = ratio.ceil().clamp(1.0, 4.0) as i32;
        let lo = -(footprint - 1) / 2;
        let hi = lo + footprint - 1;
        let (fx, fy, cx, cy) = (
            camera.fx as f32,
            camera.fy as f32,
            camera.cx as f32,
            camera.cy as f32,
        );
        let (w, h) = (camera.width as i32, camera.height as i32);
        let mut splat = |p: Point3<f32>| {
            if p.z <= 0.01 {
                return;
            }
            let u = (fx * p.x / p.z + cx).round() as i32;
            let v = (fy * p.y / p.z + cy).round() as i32;
            if u + hi < 0 || v + hi < 0 || u + lo >= w || v + lo >= h {
                return;
            }
            for dv in lo..=hi {
                let y = v + dv;
                if y < 0 || y >= h {
                    continue;
                }
                let row = y as usize * w as usize;
                for du in lo..=hi {
                    let x = u + du;
                    if x < 0 || x >= w {
                        continue;
                    }
                    let cell = &mut out.z[row + x as usize];
                    if *cell == 0.0 || p.z < *cell {
                        *cell = p.z;
                    }
                }
            }
        };
        for p in &self.static_points {
            splat(*p);
        }
        let pose = object_pose.cast::<f32>();
        for x in &self.object_points {
            splat(pose * x);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, UnitQuaternion};

    fn flat_frame(cam: &PinholeCamera, z: f32) -> DepthFrame {
        DepthFrame {
            index: 0,
            width: cam.width,
            height: cam.height,
            depth_m: vec![z; cam.width as usize * cam.height as usize],
        }
    }

    #[test]
    fn registered_wall_reprojects_at_its_depth_in_the_event_camera() {
        let depth_cam = PinholeCamera::new(100.0, 100.0, 49.5, 39.5, 100, 80).unwrap();
        let event_cam = PinholeCamera::new(200.0, 200.0, 99.5, 79.5, 200, 160).unwrap();
        // Depth camera 5 cm to the right of the event camera: a wall at 1 m stays at 1 m.
        let rig = DepthRig {
            camera: depth_cam,
            event_from_depth: Isometry3::translation(0.05, 0.0, 0.0),
        };
        let mut d = CarriedDepth::new();
        d.register(
            &flat_frame(&depth_cam, 1.0),
            &rig,
            &Point3::new(0.0, 0.0, 1.0),
            0.2,
            7,
        );
        assert!(!d.is_empty());
        assert_eq!(d.exposure_us(), Some(7));
        let mut img = DepthImage::default();
        d.render(&Isometry3::identity(), &event_cam, &mut img);
        let z = img.at(100, 80);
        assert!((z - 1.0).abs() < 1e-4, "{z}");
        // Outside the registered sphere's footprint nothing is drawn.
        assert_eq!(img.at(2, 2), 0.0);
    }

    /// A 100 x 100 px depth camera at the event camera, and its frame of a 20 x 20 px square (the object) at
    /// 0.5 m on a wall at 1 m.
    fn square_on_wall() -> (PinholeCamera, DepthRig, DepthFrame) {
        let cam = PinholeCamera::new(100.0, 100.0, 49.5, 49.5, 100, 100).unwrap();
        let rig = DepthRig {
            camera: cam,
            event_from_depth: Isometry3::identity(),
        };
        let mut frame = flat_frame(&cam, 1.0);
        for v in 40..60 {
            for u in 40..60 {
                frame.depth_m[v * 100 + u] = 0.5;
            }
        }
        (cam, rig, frame)
    }

    #[test]
    fn object_points_move_with_the_object_and_background_stays() {
        let (cam, rig, frame) = square_on_wall();
        let mut d = CarriedDepth::new();
        d.register(&frame, &rig, &Point3::new(0.0, 0.0, 0.75), 0.6, 0);
        let pose0 = Isometry3::translation(0.0, 0.0, 0.5);
        d.attach_to_object(
            &pose0,
            &Vector3::new(-0.06, -0.06, -0.01),
            &Vector3::new(0.06, 0.06, 0.01),
            0.005,
        );
        // Move the object 10 cm to the right (100 px * 0.1 / 0.5 = 20 px).
        let pose_t =
            Isometry3::from_parts(Translation3::new(0.1, 0.0, 0.5), UnitQuaternion::identity());
        let mut img = DepthImage::default();
        d.render(&pose_t, &cam, &mut img);
        assert!((img.at(70, 50) - 0.5).abs() < 1e-4, "object moved right");
        assert_eq!(
            img.at(45, 50),
            0.0,
            "the wall behind the old position was never seen"
        );
        assert!((img.at(10, 10) - 1.0).abs() < 1e-4, "background stays");
    }

    #[test]
    fn a_late_frames_object_part_is_carried_to_the_tick_and_attached_there() {
        let (cam, rig, frame) = square_on_wall();
        let (lo, hi) = (
            Vector3::new(-0.06, -0.06, -0.01),
            Vector3::new(0.06, 0.06, 0.01),
        );
        let mut d = CarriedDepth::new();
        d.register(&frame, &rig, &Point3::new(0.0, 0.0, 0.75), 0.6, 0);
        let static_before = d.static_points().len();
        // Exposed with the object at the centre; by the tick it moved 10 cm right (20 px).
        let then = Isometry3::translation(0.0, 0.0, 0.5);
        let now = Isometry3::translation(0.1, 0.0, 0.5);
        d.carry_object_part(&then, &(now * then.inverse()), &lo, &hi, 0.005);
        assert_eq!(
            d.static_points().len(),
            static_before,
            "nothing attached yet"
        );
        let mut img = DepthImage::default();
        d.render(&Isometry3::identity(), &cam, &mut img);
        assert!(
            (img.at(70, 50) - 0.5).abs() < 1e-4,
            "object part at the tick"
        );
        assert_eq!(img.at(45, 50), 0.0, "and no longer where it was exposed");
        assert!((img.at(10, 10) - 1.0).abs() < 1e-4, "background stays");
        // Attached at the pose refined at the tick, the part then moves with the object.
        d.attach_to_object(&now, &lo, &hi, 0.005);
        assert_eq!(d.object_points().len(), 400 / (d.stride as usize).pow(2));
        let later = Isometry3::translation(0.1, 0.1, 0.5);
        d.render(&later, &cam, &mut img);
        assert!((img.at(70, 70) - 0.5).abs() < 1e-4);
    }
}

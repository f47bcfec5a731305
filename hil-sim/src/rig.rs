//! The simulated sensor rig and its static surroundings: event camera, depth camera and their extrinsic, a
//! textured wall and table, and hand-like occluders that grip the object.

use crate::objects::texture::{Canvas, checker, fbm, mix, stripe, text_lines};
use crate::objects::{MeshBuilder, UvRect};
use drivers::recording::{CameraIntrinsics, CameraRig};
use nalgebra::{Isometry3, Matrix4, Translation3, UnitQuaternion, Vector3};
use scene::geometry::PinholeCamera;
use scene::mesh::{Material, Mesh, MeshError, MeshParts, Texture};
use std::sync::Arc;

/// Cameras of the simulated rig.
#[derive(Debug, Clone, PartialEq)]
pub struct SimRig {
    /// The event camera (EVK4, 1280x720), the master frame.
    pub event_camera: PinholeCamera,
    /// The depth camera (D435i depth stream, 848x480, 30 Hz).
    pub depth_camera: PinholeCamera,
    /// Takes points in the depth camera frame into the event camera frame.
    pub t_event_depth: Isometry3<f64>,
}

impl Default for SimRig {
    /// EVK4 behind a 6 mm-class lens (fx = 1000 px, 65 degrees across) and a D435i 6 cm to its right, turned 1.5
    /// degrees inwards.
    fn default() -> Self {
        Self {
            event_camera: PinholeCamera {
                fx: 1000.0,
                fy: 1000.0,
                cx: 639.5,
                cy: 359.5,
                width: 1280,
                height: 720,
            },
            depth_camera: PinholeCamera {
                fx: 425.0,
                fy: 425.0,
                cx: 423.5,
                cy: 239.5,
                width: 848,
                height: 480,
            },
            t_event_depth: Isometry3::from_parts(
                Translation3::new(0.06, 0.002, 0.0),
                UnitQuaternion::from_euler_angles(0.0, -1.5f64.to_radians(), 0.0),
            ),
        }
    }
}

impl SimRig {
    /// The rig as stored in `camera.json`.
    pub fn camera_rig(&self) -> CameraRig {
        let intr = |c: &PinholeCamera| CameraIntrinsics {
            width: c.width,
            height: c.height,
            fx: c.fx,
            fy: c.fy,
            cx: c.cx,
            cy: c.cy,
            distortion: vec![0.0; 5],
        };
        let m: Matrix4<f64> = self.t_event_depth.to_homogeneous();
        let mut rows = [[0.0; 4]; 4];
        for (r, row) in rows.iter_mut().enumerate() {
            for (c, v) in row.iter_mut().enumerate() {
                *v = m[(r, c)];
            }
        }
        rows[3] = [0.0, 0.0, 0.0, 1.0];
        CameraRig {
            event_camera: intr(&self.event_camera),
            depth_camera: intr(&self.depth_camera),
            t_event_depth: rows,
            depth_scale_m: 0.001,
        }
    }
}

/// A static mesh of the surroundings and its pose in the event camera frame.
#[derive(Debug, Clone)]
pub struct Prop {
    /// The mesh (metres, with texture).
    pub mesh: Arc<Mesh>,
    /// `T_event_prop`.
    pub pose: Isometry3<f64>,
}

fn textured_mesh(name: &str, geometry: MeshBuilder, canvas: Canvas) -> Result<Mesh, MeshError> {
    let image = canvas.into_image();
    let texture = Texture::from_srgb8(image.width(), image.height(), image.as_raw());
    Mesh::new(
        name,
        MeshParts {
            positions: geometry.positions,
            normals: geometry.normals,
            uvs: geometry.uvs,
            triangles: geometry.triangles,
            triangle_materials: vec![],
            materials: vec![Material {
                name: name.into(),
                diffuse: [1.0; 3],
                texture: texture.map(Arc::new),
            }],
        },
    )
}

const ALL_FACES: UvRect = UvRect::new(0.0, 0.0, 1.0, 1.0);

/// A wall 1.5 m behind the object's working distance and a table below it, both textured (posters, text,
/// wood grain) so that an object moving in front of them uncovers and covers structure.
pub fn surroundings(seed: u64) -> Result<Vec<Prop>, MeshError> {
    let s = seed as u32;
    let mut wall_tex = Canvas::new(1024);
    wall_tex.paint(&ALL_FACES, |u, v| {
        let n = fbm(u * 12.0, v * 8.0, s, 4);
        let tiles = checker(u, v, 9.0);
        mix(
            [0.55, 0.52, 0.48],
            [0.75, 0.73, 0.70],
            0.6 * n + 0.25 * tiles,
        )
    });
    for k in 0..6u64 {
        let x0 = 0.05 + 0.15 * k as f32;
        let area = [x0, 0.3 + 0.05 * (k % 3) as f32, x0 + 0.11, 0.75];
        wall_tex.blocks(
            &ALL_FACES,
            &text_lines(seed ^ k, area, 9, 0.025),
            [0.12, 0.12, 0.15],
        );
    }
    let mut wall = MeshBuilder::default();
    wall.cuboid(
        Vector3::new(6.0, 4.0, 0.02),
        &Isometry3::identity(),
        [ALL_FACES; 6],
    );

    let mut table_tex = Canvas::new(1024);
    table_tex.paint(&ALL_FACES, |u, v| {
        let grain = stripe(u * 40.0 + 3.0 * fbm(u * 4.0, v * 30.0, s ^ 7, 3), 1.0, 0.4);
        mix(
            [0.45, 0.30, 0.18],
            [0.62, 0.44, 0.28],
            0.5 * grain + 0.5 * fbm(u * 20.0, v * 3.0, s ^ 9, 3),
        )
    });
    let mut table = MeshBuilder::default();
    table.cuboid(
        Vector3::new(2.0, 0.03, 1.6),
        &Isometry3::identity(),
        [ALL_FACES; 6],
    );

    Ok(vec![
        Prop {
            mesh: Arc::new(textured_mesh("wall", wall, wall_tex)?),
            pose: Isometry3::translation(0.0, 0.0, 2.1),
        },
        Prop {
            mesh: Arc::new(textured_mesh("table", table, table_tex)?),
            pose: Isometry3::translation(0.0, 0.36, 1.1),
        },
    ])
}

/// A hand-like occluder: a palm with four fingers and a thumb, skin-textured, in a frame whose origin is the
/// middle of the grip and whose +x points from the palm towards the object.
pub fn hand_mesh(seed: u64) -> Result<Mesh, MeshError> {
    let s = seed as u32;
    let mut tex = Canvas::new(256);
    tex.paint(&ALL_FACES, |u, v| {
        mix(
            [0.78, 0.58, 0.46],
            [0.88, 0.70, 0.58],
            fbm(u * 16.0, v * 16.0, s ^ 0x4A, 3),
        )
    });
    let mut g = MeshBuilder::default();
    g.cuboid(
        Vector3::new(0.025, 0.085, 0.095),
        &Isometry3::translation(-0.02, 0.0, 0.0),
        [ALL_FACES; 6],
    );
    for k in 0..4 {
        let z = -0.036 + 0.024 * k as f32;
        // Fingers wrap over the object's near face.
        g.cuboid(
            Vector3::new(0.05, 0.018, 0.017),
            &Isometry3::translation(0.01, -0.05, z),
            [ALL_FACES; 6],
        );
    }
    g.cuboid(
        Vector3::new(0.045, 0.02, 0.022),
        &Isometry3::translation(0.005, 0.05, 0.0),
        [ALL_FACES; 6],
    );
    textured_mesh("hand", g, tex)
}

/// Where a hand grips an object whose bounding box is `half_extent` (half sizes, object frame): left hand
/// (`0`) on the object's -x face, right hand (`1`) on +x, palm flat against it. Returns `T_obj_hand`.
pub fn grip(side: usize, half_extent: Vector3<f64>) -> Isometry3<f64> {
    let gap = 0.008;
    if side == 0 {
        Isometry3::from_parts(
            Translation3::new(-half_extent.x - gap, 0.0, 0.0),
            UnitQuaternion::identity(),
        )
    } else {
        Isometry3::from_parts(
            Translation3::new(half_extent.x + gap, 0.0, 0.0),
            UnitQuaternion::from_axis_angle(&Vector3::y_axis(), std::f64::consts::PI),
        )
    }
}

//! What a tracked object is, independent of where it is: its label in the renders, size, box and continuous
//! symmetry axes. Fixed for the life of a track.

use nalgebra::{Isometry3, Point3, Vector3, Vector6};
use scene::mesh::Symmetry;

/// A tracked object's model (object frame, metres).
#[derive(Debug, Clone)]
pub(crate) struct ObjectModel {
    /// Label in rendered masks (1-based object index).
    pub label: u16,
    /// Diameter, metres.
    pub diameter: f64,
    /// Centre of the axis-aligned box, object frame: the point the refinement's increments rotate about.
    pub center_obj: Vector3<f64>,
    /// Box corner with the smallest coordinates, object frame.
    pub aabb_min: Vector3<f64>,
    /// Box corner with the largest coordinates, object frame.
    pub aabb_max: Vector3<f64>,
    /// Continuous symmetry axes (unit, object frame): the velocity keeps no spin about them.
    pub spin_axes: Vec<Vector3<f64>>,
}

impl ObjectModel {
    /// The model of an object labelled `label` with box `aabb_min..aabb_max` and `symmetries`.
    pub fn new(
        label: u16,
        diameter: f64,
        aabb_min: Vector3<f64>,
        aabb_max: Vector3<f64>,
        symmetries: &[Symmetry],
    ) -> Self {
        let spin_axes = symmetries
            .iter()
            .filter_map(|s| match s {
                Symmetry::Continuous { axis, .. } => Some(axis.into_inner()),
                Symmetry::Discrete(_) => None,
            })
            .collect();
        Self {
            label,
            diameter,
            center_obj: (aabb_min + aabb_max) * 0.5,
            aabb_min,
            aabb_max,
            spin_axes,
        }
    }

    /// The object's centre in the camera frame at `pose`.
    pub fn center_at(&self, pose: &Isometry3<f64>) -> Point3<f64> {
        pose * Point3::from(self.center_obj)
    }

    /// The velocity that carries `from` to `to` in `span_s` seconds (centre m/s, angular rad/s, camera frame),
    /// without the spin about any continuous symmetry axis: that rotation leaves the shape unchanged, so what the
    /// refinement reports about it is noise, and feeding it back would spin the prediction.
    pub fn observable_motion(
        &self,
        from: &Isometry3<f64>,
        to: &Isometry3<f64>,
        span_s: f64,
    ) -> Vector6<f64> {
        let v = (self.center_at(to) - self.center_at(from)) / span_s;
        let mut w = (to.rotation * from.rotation.inverse()).scaled_axis() / span_s;
        for axis in &self.spin_axes {
            let a = to.rotation * axis;
            w -= a * a.dot(&w);
        }
        Vector6::new(v.x, v.y, v.z, w.x, w.y, w.z)
    }
}

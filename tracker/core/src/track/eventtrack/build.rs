//! Setting up the tracked objects: each one's first pose checked, its render mesh (simplified within the
//! configured tolerance) registered with the renderer, its track and its place in the scene.

use super::setup::{TrackError, TrackedObject};
use crate::track::config::TrackerConfig;
use crate::track::object::ObjectTrack;
use crate::track::pose_search::ShapeSamples;
use scene::mesh::{Simplification, simplify_for_render};
use scene::render::{Renderer, SceneObject};
use std::sync::Arc;

/// The tracked objects, ready for the first tick, in object order.
pub(super) struct BuiltObjects {
    /// Names.
    pub names: Vec<String>,
    /// How each object's render mesh was simplified from its CAD mesh.
    pub render_meshes: Vec<Simplification>,
    /// The tracks.
    pub tracks: Vec<ObjectTrack>,
    /// Every object in the renderer's scene, at its first pose.
    pub scene: Vec<SceneObject>,
    /// Each object's surface samples for re-detection's whole-pose search.
    pub shapes: Vec<ShapeSamples>,
}

/// Points sampled on each mesh for the whole-pose search ([`crate::track::RedetectConfig::pose_search_views`]).
const SHAPE_SAMPLES: usize = 150;

/// Builds the tracks of `objects`, registering their render meshes with `renderer`. Refuses a first pose that is
/// not finite or lies behind the camera, and a mesh the renderer cannot take.
pub(super) fn build_objects(
    config: &TrackerConfig,
    objects: Vec<TrackedObject>,
    renderer: &mut dyn Renderer,
) -> Result<BuiltObjects, TrackError> {
    let mut built = BuiltObjects {
        names: Vec::with_capacity(objects.len()),
        render_meshes: Vec::with_capacity(objects.len()),
        tracks: Vec::with_capacity(objects.len()),
        scene: Vec::with_capacity(objects.len()),
        shapes: Vec::with_capacity(objects.len()),
    };
    for (k, o) in objects.into_iter().enumerate() {
        check_first_pose(&o)?;
        let aabb = o.mesh.aabb();
        let label = (k + 1) as u16;
        let diameter = if o.diameter.is_finite() && o.diameter > 0.0 {
            o.diameter
        } else {
            o.mesh.diameter()
        };
        let roi_pixel_m = config.roi.roi_scale * diameter / f64::from(config.roi.roi_size);
        let tolerance_m = if o.mesh.triangles().len() > config.execution.render_mesh_simplify_above
        {
            config.execution.render_mesh_tolerance_px * roi_pixel_m
        } else {
            0.0
        };
        let (render_mesh, simplification) = simplify_for_render(&o.mesh, tolerance_m);
        built.render_meshes.push(simplification);
        let mesh_id =
            renderer
                .add_mesh(Arc::new(render_mesh))
                .map_err(|source| TrackError::Render {
                    object: o.name.clone(),
                    source,
                })?;
        built.shapes.push(ShapeSamples::new(
            &o.mesh.sample_surface_seeded(SHAPE_SAMPLES, 0x5eed),
            &aabb.center().coords,
        ));
        built.tracks.push(ObjectTrack::new(
            label,
            diameter,
            aabb.min.coords,
            aabb.max.coords,
            o.first_pose,
            o.first_t_us,
            &o.symmetries,
            config,
        ));
        built.scene.push(SceneObject {
            mesh: mesh_id,
            pose: o.first_pose,
            id: label,
        });
        built.names.push(o.name);
    }
    Ok(built)
}

/// Refuses a first pose that is not finite or lies behind the camera.
fn check_first_pose(o: &TrackedObject) -> Result<(), TrackError> {
    let p = &o.first_pose;
    if !(p.translation.vector.iter().all(|v| v.is_finite())
        && p.rotation.coords.iter().all(|v| v.is_finite()))
    {
        return Err(TrackError::BadFirstPose {
            object: o.name.clone(),
            reason: "not finite",
        });
    }
    if p.translation.z <= 0.0 {
        return Err(TrackError::BadFirstPose {
            object: o.name.clone(),
            reason: "behind the camera (z <= 0)",
        });
    }
    Ok(())
}

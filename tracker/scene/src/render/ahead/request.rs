//! What a render ahead answers: an owned copy of a scene and camera, compared bit for bit with later requests.

use crate::geometry::PinholeCamera;
use crate::render::{BackgroundMesh, Lighting, NormalCoverage, Scene, SceneObject};
use nalgebra::Isometry3;

/// An owned copy of everything a render depends on besides the registered meshes: the scene and the camera
/// (for a ROI render, the cropped camera).
#[derive(Debug)]
pub(super) struct AheadRequest {
    objects: Vec<SceneObject>,
    background: Vec<BackgroundMesh>,
    lighting: Lighting,
    near: f64,
    shade_intensity: bool,
    normals: NormalCoverage,
    camera: Option<PinholeCamera>,
}

impl Default for AheadRequest {
    fn default() -> Self {
        Self {
            objects: Vec::new(),
            background: Vec::new(),
            lighting: Lighting::default(),
            near: Scene::DEFAULT_NEAR,
            shade_intensity: true,
            normals: NormalCoverage::Everywhere,
            camera: None,
        }
    }
}

impl AheadRequest {
    /// Makes `self` the request of rendering `scene` with `camera`, reusing its buffers.
    pub(super) fn assign(&mut self, scene: &Scene<'_>, camera: &PinholeCamera) {
        self.assign_scene(scene);
        self.camera = Some(*camera);
    }

    /// Makes `self` equal to `other`, reusing its buffers (a derived `clone_from` would allocate new ones).
    pub(super) fn copy_from(&mut self, other: &Self) {
        self.assign_scene(&other.scene());
        self.camera = other.camera;
    }

    /// Copies `scene` into `self`'s buffers.
    fn assign_scene(&mut self, scene: &Scene<'_>) {
        self.objects.clear();
        self.objects.extend_from_slice(scene.objects);
        self.background.clear();
        self.background.extend_from_slice(scene.background);
        self.lighting = scene.lighting;
        self.near = scene.near;
        self.shade_intensity = scene.shade_intensity;
        self.normals = scene.normals;
    }

    /// Whether rendering `scene` with `camera` is this request, bit for bit (so it gives the identical image).
    pub(super) fn is(&self, scene: &Scene<'_>, camera: &PinholeCamera) -> bool {
        let Some(own) = &self.camera else {
            return false;
        };
        let bits = |a: f64, b: f64| a.to_bits() == b.to_bits();
        let same_pose = |a: &Isometry3<f64>, b: &Isometry3<f64>| {
            a.translation
                .vector
                .iter()
                .chain(a.rotation.coords.iter())
                .zip(b.translation.vector.iter().chain(b.rotation.coords.iter()))
                .all(|(x, y)| bits(*x, *y))
        };
        let (l, m) = (&self.lighting, &scene.lighting);
        bits(own.fx, camera.fx)
            && bits(own.fy, camera.fy)
            && bits(own.cx, camera.cx)
            && bits(own.cy, camera.cy)
            && own.width == camera.width
            && own.height == camera.height
            && bits(self.near, scene.near)
            && self.shade_intensity == scene.shade_intensity
            && self.normals == scene.normals
            && l.direction
                .iter()
                .zip(m.direction.iter())
                .all(|(x, y)| bits(*x, *y))
            && bits(l.ambient, m.ambient)
            && bits(l.diffuse, m.diffuse)
            && self.objects.len() == scene.objects.len()
            && self
                .objects
                .iter()
                .zip(scene.objects)
                .all(|(a, b)| a.mesh == b.mesh && a.id == b.id && same_pose(&a.pose, &b.pose))
            && self.background.len() == scene.background.len()
            && self
                .background
                .iter()
                .zip(scene.background)
                .all(|(a, b)| a.mesh == b.mesh && same_pose(&a.pose, &b.pose))
    }

    /// The camera to render with; `None` before the first [`Self::assign`].
    pub(super) fn camera(&self) -> Option<PinholeCamera> {
        self.camera
    }

    /// The scene to render.
    pub(super) fn scene(&self) -> Scene<'_> {
        Scene {
            objects: &self.objects,
            background: &self.background,
            lighting: self.lighting,
            near: self.near,
            shade_intensity: self.shade_intensity,
            normals: self.normals,
        }
    }
}

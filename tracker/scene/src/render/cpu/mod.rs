//! The deterministic CPU rasteriser.

pub(super) mod prepared;
mod raster;

use super::{
    MASK_BACKGROUND, MAX_PIXELS, MeshId, NormalCoverage, RenderDevice, RenderError, RenderTarget,
    Renderer, Scene, scene::MASK_EMPTY, surface_grid_stride,
};
use crate::geometry::PinholeCamera;
use crate::geometry::se3::to_glam_affine;
use crate::mesh::Mesh;
use glam::{Mat3A, Vec3A};
use nalgebra::Isometry3;
use prepared::{Albedo, PreparedMesh};
use raster::{Cull, NO_INSTANCE, Projector, RasterVertex, VisBuffer};
use std::sync::Arc;

/// Largest image side the fixed-point rasteriser supports, pixels.
const MAX_SIDE: u32 = 1 << 15;

/// One posed instance of the current render.
#[derive(Debug, Clone, Copy)]
struct Instance {
    mesh: usize,
    rotation: Mat3A,
    mask: u16,
}

/// A deterministic CPU rasteriser: z-buffered, perspective-correct texturing with bilinear sampling, Lambertian +
/// ambient shading. Produces depth, normals, object mask and intensity.
///
/// Surfaces are two-sided (open meshes such as a bowl's thin wall render from both sides), except that back faces of
/// object meshes that are closed and consistently wound are culled, which halves the work without changing the image.
///
/// Rendering proceeds in two passes: visibility (nearest fragment per pixel centre, exact integer edge functions with
/// the top-left rule) then shading of each visible pixel once. All scratch memory is kept between renders, so repeated
/// renders at the same size do not allocate. Output is bit-identical for identical inputs.
#[derive(Debug, Default)]
pub struct CpuRenderer {
    /// Shared with the renderers [`Renderer::fork`] made (prepared meshes never change).
    meshes: Vec<Arc<PreparedMesh>>,
    vis: VisBuffer,
    view: Vec<Vec3A>,
    codes: Vec<u8>,
    screen: Vec<RasterVertex>,
    instances: Vec<Instance>,
    /// Per instance: visible pixels, then the pitch of its normal grid (pixels; 1 = every pixel).
    normal_stride: Vec<usize>,
}

impl CpuRenderer {
    /// A renderer with no meshes registered.
    pub fn new() -> Self {
        Self::default()
    }

    /// Validates the scene and fills `self.instances` (objects first, then background).
    fn collect_instances(&mut self, scene: &Scene<'_>) -> Result<(), RenderError> {
        let total = scene.objects.len() + scene.background.len();
        if total >= usize::from(NO_INSTANCE) {
            return Err(RenderError::TooManyInstances(total));
        }
        self.instances.clear();
        let items = scene
            .objects
            .iter()
            .enumerate()
            .map(|(i, o)| (o.mesh, &o.pose, Some(o.id), i))
            .chain(
                scene
                    .background
                    .iter()
                    .enumerate()
                    .map(|(i, b)| (b.mesh, &b.pose, None, i)),
            );
        for (mesh, pose, id, i) in items {
            let what = || match id {
                Some(id) => format!("object #{i} (id {id})"),
                None => format!("background mesh #{i}"),
            };
            let mesh_index = mesh.0 as usize;
            if mesh_index >= self.meshes.len() {
                return Err(RenderError::UnknownMesh(mesh));
            }
            if let Some(id) = id
                && (id == MASK_EMPTY || id == MASK_BACKGROUND)
            {
                return Err(RenderError::ReservedObjectId(id));
            }
            if !pose_is_finite(pose) {
                return Err(RenderError::NonFinitePose { what: what() });
            }
            self.instances.push(Instance {
                mesh: mesh_index,
                rotation: to_glam_affine(pose).matrix3,
                mask: id.unwrap_or(MASK_BACKGROUND),
            });
        }
        Ok(())
    }

    /// Visibility pass for one instance.
    fn draw_instance(&mut self, proj: &Projector, instance: u16, pose: &Isometry3<f64>) {
        let info = self.instances[usize::from(instance)];
        let mesh = &self.meshes[info.mesh];
        // Back faces of closed objects are hidden by their front faces; background meshes (which the camera may be
        // inside of, like a room) are always drawn two-sided.
        let cull = Cull(if info.mask == MASK_BACKGROUND {
            0
        } else {
            mesh.cull
        });
        let affine = to_glam_affine(pose);
        self.view.clear();
        self.codes.clear();
        self.screen.clear();
        for &p in &mesh.positions {
            let q = affine.transform_point3a(p);
            let code = proj.outcode(q);
            self.view.push(q);
            self.codes.push(code);
            // Only vertices inside every plane are projected; others are handled by clipping.
            self.screen.push(if code == 0 {
                proj.project(q, Vec3A::ZERO)
            } else {
                proj.project(Vec3A::Z, Vec3A::ZERO)
            });
        }
        for (t, tri) in mesh.triangles.iter().enumerate() {
            let [a, b, c] = tri.map(|i| i as usize);
            let codes = [self.codes[a], self.codes[b], self.codes[c]];
            let projected = (codes[0] | codes[1] | codes[2] == 0)
                .then(|| [self.screen[a], self.screen[b], self.screen[c]]);
            raster::draw_triangle(
                &mut self.vis,
                proj,
                instance,
                t as u32,
                [self.view[a], self.view[b], self.view[c]],
                codes,
                projected,
                cull,
            );
        }
    }

    /// Sets each instance's normal grid pitch for `coverage` (1 everywhere when intensity is shaded).
    fn plan_normals(&mut self, scene: &Scene<'_>) {
        self.normal_stride.clear();
        self.normal_stride.resize(self.instances.len(), 0);
        let max_samples = match scene.normals {
            NormalCoverage::SurfaceGrid { max_samples } if !scene.shade_intensity => max_samples,
            _ => {
                self.normal_stride.fill(1);
                return;
            }
        };
        for &inst in &self.vis.instance {
            if let Some(count) = self.normal_stride.get_mut(usize::from(inst)) {
                *count += 1;
            }
        }
        for (count, instance) in self.normal_stride.iter_mut().zip(&self.instances) {
            *count = if instance.mask == MASK_BACKGROUND {
                1
            } else {
                surface_grid_stride(*count, max_samples)
            };
        }
    }

    /// Shading pass: resolves every pixel into the target (visible ones shaded, the rest "nothing rendered"), so
    /// the target needs no clearing before it.
    fn shade(&self, scene: &Scene<'_>, camera: &PinholeCamera, target: &mut RenderTarget) {
        let l = &scene.lighting;
        let light = Vec3A::new(
            l.direction.x as f32,
            l.direction.y as f32,
            l.direction.z as f32,
        )
        .normalize_or_zero();
        let (ambient, diffuse) = (l.ambient as f32, l.diffuse as f32);
        let (fx, fy, cx, cy) = (
            camera.fx as f32,
            camera.fy as f32,
            camera.cx as f32,
            camera.cy as f32,
        );
        let (inv_fx, inv_fy) = (1.0 / fx, 1.0 / fy);
        let width = self.vis.width;
        for (v, row) in self.vis.instance.chunks_exact(width.max(1)).enumerate() {
            let ray_y = (v as f32 - cy) * inv_fy;
            for (u, &inst) in row.iter().enumerate() {
                let idx = v * width + u;
                if inst == NO_INSTANCE {
                    target.depth[idx] = 0.0;
                    target.mask[idx] = MASK_EMPTY;
                    target.normals[idx] = [0.0; 3];
                    target.intensity[idx] = 0.0;
                    continue;
                }
                let info = &self.instances[usize::from(inst)];
                target.depth[idx] = 1.0 / self.vis.inv_z[idx];
                target.mask[idx] = info.mask;
                let stride = self.normal_stride[usize::from(inst)];
                if stride > 1 && (u % stride != 0 || v % stride != 0) {
                    target.normals[idx] = [0.0; 3];
                    target.intensity[idx] = 0.0;
                    continue;
                }
                let mesh = &self.meshes[info.mesh];
                let tri = self.vis.triangle[idx] as usize;
                let [b1, b2] = self.vis.bary[idx];
                let b0 = 1.0 - b1 - b2;
                let [i0, i1, i2] = mesh.triangles[tri].map(|i| i as usize);
                let n_obj = if mesh.normals.is_empty() {
                    mesh.face_normals[tri]
                } else {
                    mesh.normals[i0] * b0 + mesh.normals[i1] * b1 + mesh.normals[i2] * b2
                };
                let ray = Vec3A::new((u as f32 - cx) * inv_fx, ray_y, 1.0);
                let mut n = (info.rotation * n_obj).normalize_or_zero();
                if n == Vec3A::ZERO {
                    n = -ray.normalize();
                } else if n.dot(ray) > 0.0 {
                    n = -n;
                }
                target.normals[idx] = n.to_array();
                if !scene.shade_intensity {
                    target.intensity[idx] = 0.0;
                    continue;
                }
                let albedo = match &mesh.albedo[mesh.triangle_materials[tri] as usize] {
                    Albedo::Constant(a) => *a,
                    Albedo::Textured(texture) => {
                        texture.sample(mesh.uvs[i0] * b0 + mesh.uvs[i1] * b1 + mesh.uvs[i2] * b2)
                    }
                };
                target.intensity[idx] = albedo * (ambient + diffuse * n.dot(light).max(0.0));
            }
        }
    }
}

fn pose_is_finite(pose: &Isometry3<f64>) -> bool {
    pose.translation.vector.iter().all(|v| v.is_finite())
        && pose.rotation.coords.iter().all(|v| v.is_finite())
}

impl Renderer for CpuRenderer {
    fn device(&self) -> RenderDevice {
        RenderDevice::CpuRasteriser
    }

    fn fork(&self) -> Option<Box<dyn Renderer + Send>> {
        Some(Box::new(Self {
            meshes: self.meshes.clone(),
            ..Self::default()
        }))
    }

    fn add_mesh(&mut self, mesh: Arc<Mesh>) -> Result<MeshId, RenderError> {
        let id = u32::try_from(self.meshes.len())
            .map_err(|_| RenderError::Backend("too many meshes".into()))?;
        self.meshes.push(Arc::new(PreparedMesh::new(mesh)));
        Ok(MeshId(id))
    }

    fn render(
        &mut self,
        scene: &Scene<'_>,
        camera: &PinholeCamera,
        target: &mut RenderTarget,
    ) -> Result<(), RenderError> {
        camera.validate()?;
        let (w, h) = (camera.width, camera.height);
        if w > MAX_SIDE || h > MAX_SIDE || u64::from(w) * u64::from(h) > MAX_PIXELS {
            return Err(RenderError::ImageTooLarge {
                width: w,
                height: h,
            });
        }
        if !(scene.near.is_finite() && scene.near > 0.0) {
            return Err(RenderError::InvalidNear(scene.near));
        }
        self.collect_instances(scene)?;
        target.resize_for_overwrite(w, h);
        target.camera = Some(*camera);
        self.vis.reset(w as usize, h as usize);
        let proj = Projector::new(
            camera.fx as f32,
            camera.fy as f32,
            camera.cx as f32,
            camera.cy as f32,
            w,
            h,
            scene.near as f32,
        );
        let poses = scene
            .objects
            .iter()
            .map(|o| &o.pose)
            .chain(scene.background.iter().map(|b| &b.pose));
        for (instance, pose) in poses.enumerate() {
            // Bounded by the TooManyInstances check above.
            self.draw_instance(&proj, instance as u16, pose);
        }
        self.plan_normals(scene);
        self.shade(scene, camera, target);
        Ok(())
    }
}

//! Quick-look renders of library objects (for `hil-sim objects --preview` and for people checking the library).

use super::model::ObjectModel;
use image::GrayImage;
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion};
use scene::geometry::{PinholeCamera, Roi};
use scene::mesh::MeshError;
use scene::render::{CpuRenderer, RenderError, RenderTarget, Renderer, Scene, SceneObject};
use std::sync::Arc;

/// Why a preview could not be rendered.
#[derive(Debug, thiserror::Error)]
pub enum PreviewError {
    /// The object's geometry is invalid.
    #[error("object '{name}': {source}")]
    Mesh {
        /// The object.
        name: String,
        /// What is wrong.
        #[source]
        source: MeshError,
    },
    /// The renderer refused the scene.
    #[error("object '{name}': {source}")]
    Render {
        /// The object.
        name: String,
        /// What the renderer reported.
        #[source]
        source: RenderError,
    },
}

/// Renders `object` from a three-quarter view, 0.5 m away, into a `size x size` sRGB grey image whose crop is 1.2 x the
/// object's diameter (the tracker's ROI). Background is black.
pub fn render_preview<O: ObjectModel + ?Sized>(
    object: &O,
    size: u32,
) -> Result<GrayImage, PreviewError> {
    let name = object.name().to_string();
    let mesh = object.to_mesh().map_err(|source| PreviewError::Mesh {
        name: name.clone(),
        source,
    })?;
    let render_err = |source| PreviewError::Render {
        name: name.clone(),
        source,
    };
    let diameter = mesh.diameter();
    let mut renderer = CpuRenderer::new();
    let id = renderer.add_mesh(Arc::new(mesh)).map_err(render_err)?;
    let pose = Isometry3::from_parts(
        Translation3::new(0.0, 0.0, 0.5),
        UnitQuaternion::from_euler_angles(-2.0, 0.2, 0.6),
    );
    let camera = PinholeCamera::from_horizontal_fov(70f64.to_radians(), 1280, 720)
        .map_err(|e| render_err(e.into()))?;
    let roi = Roi::around_object(
        &camera,
        &(pose * Point3::origin()),
        diameter,
        1.2,
        size.max(1),
    )
    .map_err(|e| render_err(e.into()))?;
    let mut target = RenderTarget::new();
    let objects = [SceneObject {
        mesh: id,
        pose,
        id: 1,
    }];
    renderer
        .render_roi(&Scene::objects(&objects), &camera, &roi, &mut target)
        .map_err(render_err)?;
    let srgb = |l: f32| {
        let l = l.clamp(0.0, 1.0);
        let c = if l <= 0.003_130_8 {
            12.92 * l
        } else {
            1.055 * l.powf(1.0 / 2.4) - 0.055
        };
        (c * 255.0).round() as u8
    };
    Ok(GrayImage::from_fn(
        target.width(),
        target.height(),
        |x, y| {
            let i = y as usize * target.width() as usize + x as usize;
            image::Luma([srgb(target.intensity()[i])])
        },
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::objects::{ObjectKind, generate};

    #[test]
    fn preview_shows_the_object() {
        let img = render_preview(&generate(ObjectKind::Can, 0), 64).unwrap();
        assert_eq!(img.dimensions(), (64, 64));
        let lit = img.pixels().filter(|p| p.0[0] > 0).count();
        assert!(lit > 64 * 64 / 10, "{lit} lit pixels");
        assert_eq!(img.get_pixel(0, 0).0[0], 0, "corner is background");
    }
}

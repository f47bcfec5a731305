//! What every generated object offers the writer, the previews and the simulator: a name, a textured triangle mesh
//! and its shape symmetries.

use super::builder::MeshBuilder;
use image::RgbImage;
use scene::mesh::{Material, Mesh, MeshError, MeshParts, ObjectInfo, Symmetry, Texture};
use std::sync::Arc;

/// A generated object: geometry (object frame, metres, centred on its bounding box), one sRGB texture atlas and the
/// shape symmetries ADD-S / MSSD evaluation and `models_info.json` use.
pub trait ObjectModel {
    /// The object's name: the file stem of its model and its name in the ground truth (letters, digits and `_`,
    /// not starting with a digit).
    fn name(&self) -> &str;
    /// Vertices, normals, texture coordinates and triangles.
    fn geometry(&self) -> &MeshBuilder;
    /// The diffuse texture atlas, sRGB.
    fn texture(&self) -> &RgbImage;
    /// Shape symmetries (identity excluded).
    fn symmetries(&self) -> &[Symmetry];

    /// The object as a renderable tracker mesh (the same data [`super::write_object`] stores).
    fn to_mesh(&self) -> Result<Mesh, MeshError> {
        let texture = self.texture();
        let texture = Texture::from_srgb8(texture.width(), texture.height(), texture.as_raw());
        let g = self.geometry();
        Mesh::new(
            self.name(),
            MeshParts {
                positions: g.positions.clone(),
                normals: g.normals.clone(),
                uvs: g.uvs.clone(),
                triangles: g.triangles.clone(),
                triangle_materials: vec![],
                materials: vec![Material {
                    name: self.name().into(),
                    diffuse: [1.0; 3],
                    texture: texture.map(Arc::new),
                }],
            },
        )
    }

    /// BOP-style object information (diameter and extent measured from the mesh, plus the symmetries).
    fn info(&self) -> Result<ObjectInfo, MeshError> {
        Ok(ObjectInfo::from_mesh(
            &self.to_mesh()?,
            self.symmetries().to_vec(),
        ))
    }
}

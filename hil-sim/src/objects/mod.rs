//! The procedural object library: textured household objects and tools resembling the Event6D / YCB test categories
//! (boxes, can, bottle, mug, bowl, banana, hammer, spatula, drill, marker, wine glass), generated entirely by this
//! code, with realistic sizes in metres and BOP-style object information (diameter, shape symmetries).
//!
//! Each object is a single-material triangle mesh with one texture atlas; textures are busy (labels, stripes, noise)
//! so that moving surfaces produce events. Objects are centred on their bounding box; the symmetry axis of round
//! objects is the object z axis. [`write_object`] stores an object as OBJ + MTL + PNG that
//! [`scene::mesh::load_obj`] reads back.
//!
//! [`novel`] makes objects of shape families the library lacks (superquadrics, star prisms, tori, brackets,
//! twisted prisms, holed frustums), each from a seed, for checking the tracker on shapes it was not tuned on.

mod builder;
mod model;
pub mod novel;
mod packaging;
mod preview;
mod solid;
pub(crate) mod tableware;
pub mod texture;

pub use texture::TEXTURE_SIZE;
mod tools;
mod write;

pub use builder::{MeshBuilder, UvRect};
pub use model::ObjectModel;
pub use novel::{NovelFamily, NovelObject};
pub use preview::{PreviewError, render_preview};
pub use write::{ObjectFiles, ObjectWriteError, models_info_json, write_library, write_object};

use image::RgbImage;
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use scene::mesh::{Mesh, MeshError, ObjectInfo, Symmetry};

/// The categories of the library.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum ObjectKind {
    /// A cereal/cracker box, 16 x 6 x 21 cm.
    CrackerBox,
    /// A small pudding box, 9 x 3.5 x 11 cm.
    PuddingBox,
    /// A food can, 6.8 cm across, 10 cm tall.
    Can,
    /// A squeeze bottle (mustard-like) with shoulder, neck and cap, 19 cm tall.
    Bottle,
    /// A mug with a handle, 8.2 cm across, 9.5 cm tall.
    Mug,
    /// A bowl, 16 cm across, 5.5 cm tall.
    Bowl,
    /// A curved, tapered banana, about 20 cm long.
    Banana,
    /// A claw hammer, 32 cm long.
    Hammer,
    /// A kitchen turner (spatula) with an offset blade, 31 cm long.
    Spatula,
    /// A cordless drill with chuck, grip and battery.
    Drill,
    /// A marker pen with cap, 13 cm long.
    Marker,
    /// A stemmed wine glass, 20 cm tall.
    WineGlass,
}

impl ObjectKind {
    /// Every kind, in library order (BOP object ids are this index + 1).
    pub const ALL: [ObjectKind; 12] = [
        ObjectKind::CrackerBox,
        ObjectKind::PuddingBox,
        ObjectKind::Can,
        ObjectKind::Bottle,
        ObjectKind::Mug,
        ObjectKind::Bowl,
        ObjectKind::Banana,
        ObjectKind::Hammer,
        ObjectKind::Spatula,
        ObjectKind::Drill,
        ObjectKind::Marker,
        ObjectKind::WineGlass,
    ];

    /// File-name-safe name, e.g. `cracker_box`.
    pub fn name(self) -> &'static str {
        match self {
            ObjectKind::CrackerBox => "cracker_box",
            ObjectKind::PuddingBox => "pudding_box",
            ObjectKind::Can => "can",
            ObjectKind::Bottle => "bottle",
            ObjectKind::Mug => "mug",
            ObjectKind::Bowl => "bowl",
            ObjectKind::Banana => "banana",
            ObjectKind::Hammer => "hammer",
            ObjectKind::Spatula => "spatula",
            ObjectKind::Drill => "drill",
            ObjectKind::Marker => "marker",
            ObjectKind::WineGlass => "wine_glass",
        }
    }

    /// The kind with this [`ObjectKind::name`], if any.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == name)
    }
}

/// A generated object: geometry (object frame, metres), texture atlas (sRGB) and shape symmetries.
#[derive(Debug, Clone)]
pub struct ProceduralObject {
    /// Its category.
    pub kind: ObjectKind,
    /// Vertices, normals, texture coordinates and triangles; centred on the bounding box.
    pub geometry: MeshBuilder,
    /// The diffuse texture atlas, sRGB, `TEXTURE_SIZE` square.
    pub texture: RgbImage,
    /// Shape symmetries (identity excluded), as used by ADD-S / MSSD evaluation.
    pub symmetries: Vec<Symmetry>,
}

/// A rotation by `angle` about a coordinate axis, as a symmetry.
fn turn(axis: Vector3<f64>, angle: f64) -> Symmetry {
    Symmetry::Discrete(Isometry3::from_parts(
        Translation3::identity(),
        UnitQuaternion::from_scaled_axis(axis * angle),
    ))
}

fn box_symmetries() -> Vec<Symmetry> {
    use std::f64::consts::PI;
    vec![
        turn(Vector3::x(), PI),
        turn(Vector3::y(), PI),
        turn(Vector3::z(), PI),
    ]
}

fn axial_symmetry() -> Symmetry {
    Symmetry::Continuous {
        axis: Vector3::z_axis(),
        offset: Point3::origin(),
    }
}

/// Generates one object. Geometry depends only on the kind; `seed` varies the texture (text layout, noise, colours).
pub fn generate(kind: ObjectKind, seed: u64) -> ProceduralObject {
    let seed = seed ^ (kind as u64 + 1).wrapping_mul(0x9e37_79b9_7f4a_7c15);
    let (mut geometry, texture, symmetries) = match kind {
        ObjectKind::CrackerBox => {
            let (g, t) = packaging::cardboard_box(Vector3::new(0.16, 0.06, 0.21), seed);
            (g, t, box_symmetries())
        }
        ObjectKind::PuddingBox => {
            let (g, t) = packaging::cardboard_box(Vector3::new(0.09, 0.035, 0.11), seed);
            (g, t, box_symmetries())
        }
        ObjectKind::Can => {
            let (g, t) = packaging::can(seed);
            (
                g,
                t,
                vec![axial_symmetry(), turn(Vector3::x(), std::f64::consts::PI)],
            )
        }
        ObjectKind::Bottle => {
            let (g, t) = packaging::bottle(seed);
            (g, t, vec![axial_symmetry()])
        }
        ObjectKind::Mug => {
            let (g, t) = tableware::mug(seed);
            (g, t, vec![])
        }
        ObjectKind::Bowl => {
            let (g, t) = tableware::bowl(seed);
            (g, t, vec![axial_symmetry()])
        }
        ObjectKind::Marker => {
            let (g, t) = tableware::marker(seed);
            (g, t, vec![axial_symmetry()])
        }
        ObjectKind::WineGlass => {
            let (g, t) = tableware::wine_glass(seed);
            (g, t, vec![axial_symmetry()])
        }
        ObjectKind::Banana => {
            let (g, t) = tools::banana(seed);
            (g, t, vec![])
        }
        ObjectKind::Hammer => {
            let (g, t) = tools::hammer(seed);
            (g, t, vec![])
        }
        ObjectKind::Spatula => {
            let (g, t) = tools::spatula(seed);
            (g, t, vec![])
        }
        ObjectKind::Drill => {
            let (g, t) = tools::drill(seed);
            (g, t, vec![])
        }
    };
    geometry.center_on_bounding_box();
    ProceduralObject {
        kind,
        geometry,
        texture,
        symmetries,
    }
}

/// The whole library, in [`ObjectKind::ALL`] order.
pub fn library(seed: u64) -> Vec<ProceduralObject> {
    ObjectKind::ALL
        .into_iter()
        .map(|k| generate(k, seed))
        .collect()
}

impl ProceduralObject {
    /// The object's name (its kind's name); also the file stem used by [`write_object`].
    pub fn name(&self) -> &'static str {
        self.kind.name()
    }

    /// The object as a renderable tracker mesh (same data [`write_object`] stores).
    pub fn to_mesh(&self) -> Result<Mesh, MeshError> {
        ObjectModel::to_mesh(self)
    }

    /// BOP-style object information (diameter and extent measured from the mesh, plus the symmetries).
    pub fn info(&self) -> Result<ObjectInfo, MeshError> {
        ObjectModel::info(self)
    }
}

impl ObjectModel for ProceduralObject {
    fn name(&self) -> &str {
        self.kind.name()
    }
    fn geometry(&self) -> &MeshBuilder {
        &self.geometry
    }
    fn texture(&self) -> &RgbImage {
        &self.texture
    }
    fn symmetries(&self) -> &[Symmetry] {
        &self.symmetries
    }
}

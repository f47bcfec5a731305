//! Objects of shape families the procedural library lacks, each made from a seed, for checking the tracker on
//! shapes it was not tuned on: superquadrics, bevelled star prisms, tori and torus segments, L / T / cross brackets,
//! twisted and tapered prisms, and holed frustums.
//!
//! Every object is one closed, consistently wound surface (edges shared by exactly two triangles), its
//! bounding-box diagonal 9 to 24.5 cm (5 to 24.5 cm in diameter), centred on the box, with a busy procedural
//! texture (stripes, checks, blobs or rings, grain and printed-label blocks) so that moving surfaces produce events
//! inside the silhouette. Its shape symmetries are
//! declared as the library's are (geometry only, texture ignored). The same family and seed give the same mesh and
//! texture, byte for byte; the object is named `novel_<family>_<seed>`.
//!
//! This module holds the families, their names and the entry point [`generate`]; each family's shape and
//! symmetries live in a file of their own, the shared prism sweep in `extrude`, and the paint in `texture`.

mod bracket;
mod extrude;
mod holed_frustum;
mod parts;
mod star_prism;
mod superquadric;
#[cfg(test)]
mod tests;
mod texture;
mod torus;
mod twisted_prism;

use bracket::bracket;
use holed_frustum::holed_frustum;
use star_prism::star_prism;
use superquadric::superquadric;
use torus::torus;
use twisted_prism::twisted_prism;

use super::builder::MeshBuilder;
use super::model::ObjectModel;
use crate::rng::SeedRng;
use image::RgbImage;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use scene::mesh::Symmetry;

/// The shape families.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum NovelFamily {
    /// A superellipsoid: three different semi-axes, random squareness exponents (from pillow-like to diamond-like).
    Superquadric,
    /// A bevelled prism over a regular star of 4 to 8 points.
    StarPrism,
    /// A whole torus (`seed / 6` even) or a 200-300 degree segment with flat ends (a C-ring; odd), elliptical
    /// cross-section.
    Torus,
    /// An L, T or cross of bars (by `seed / 6` mod 3) extruded into a bevelled bracket, always asymmetric.
    Bracket,
    /// An irregular 3- to 7-cornered prism, twisted by 45 to 150 degrees and tapered along its length.
    TwistedPrism,
    /// A frustum with an axial through hole: round (`seed / 6` even) or 5-, 6- or 8-sided (odd).
    HoledFrustum,
}

impl NovelFamily {
    /// Every family; `novel:SEED` takes `ALL[SEED % 6]`.
    pub const ALL: [NovelFamily; 6] = [
        NovelFamily::Superquadric,
        NovelFamily::StarPrism,
        NovelFamily::Torus,
        NovelFamily::Bracket,
        NovelFamily::TwistedPrism,
        NovelFamily::HoledFrustum,
    ];

    /// The family's name in object names, e.g. `star_prism`.
    pub fn name(self) -> &'static str {
        match self {
            NovelFamily::Superquadric => "superquadric",
            NovelFamily::StarPrism => "star_prism",
            NovelFamily::Torus => "torus",
            NovelFamily::Bracket => "bracket",
            NovelFamily::TwistedPrism => "twisted_prism",
            NovelFamily::HoledFrustum => "holed_frustum",
        }
    }

    /// The family with this [`NovelFamily::name`], if any.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|f| f.name() == name)
    }

    /// The family `novel:SEED` makes: consecutive seeds go through every family in turn.
    pub fn for_seed(seed: u64) -> Self {
        Self::ALL[(seed % Self::ALL.len() as u64) as usize]
    }
}

/// The object name of a family and seed, `novel_<family>_<seed>` (a valid ROS name token).
pub fn novel_name(family: NovelFamily, seed: u64) -> String {
    format!("novel_{}_{seed}", family.name())
}

/// Reads `novel:SEED` (the family [`NovelFamily::for_seed`] picks) or an object name `novel_<family>_<seed>` (as
/// [`novel_name`] writes it: no leading zeros).
pub fn parse_spec(spec: &str) -> Option<(NovelFamily, u64)> {
    let digits = |s: &str| -> Option<u64> {
        if s.is_empty() || !s.bytes().all(|b| b.is_ascii_digit()) {
            return None;
        }
        s.parse().ok()
    };
    if let Some(seed) = spec.strip_prefix("novel:") {
        let seed = digits(seed)?;
        return Some((NovelFamily::for_seed(seed), seed));
    }
    let (family, seed) = spec.strip_prefix("novel_")?.rsplit_once('_')?;
    let family = NovelFamily::from_name(family)?;
    let seed = digits(seed).filter(|n| n.to_string() == seed)?;
    Some((family, seed))
}

/// A generated object of a novel family.
#[derive(Debug, Clone)]
pub struct NovelObject {
    /// Its family.
    pub family: NovelFamily,
    /// Its seed.
    pub seed: u64,
    /// `novel_<family>_<seed>`.
    pub name: String,
    /// Vertices, normals, texture coordinates and triangles; centred on the bounding box.
    pub geometry: MeshBuilder,
    /// The diffuse texture atlas, sRGB, `TEXTURE_SIZE` square.
    pub texture: RgbImage,
    /// Shape symmetries (identity excluded), in the centred object frame.
    pub symmetries: Vec<Symmetry>,
}

impl ObjectModel for NovelObject {
    fn name(&self) -> &str {
        &self.name
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

/// Bounding-box diagonal of every object, metres: a shape drawn outside is scaled into it.
pub const DIAGONAL_M: (f32, f32) = (0.09, 0.245);

/// Crease angle of the normals: edges sharper than this are shaded flat on each side.
const CREASE_DEG: f32 = 35.0;

/// Generates the object of `family` and `seed`.
pub fn generate(family: NovelFamily, seed: u64) -> NovelObject {
    let mut rng = SeedRng::new(seed ^ (family as u64 + 1).wrapping_mul(0xA076_1D64_78BD_642F));
    // Families with variants take them in turn along the seeds that `novel:SEED` gives the family (SEED, SEED + 6,
    // ...), so consecutive seeds cover them all.
    let variant = (seed / NovelFamily::ALL.len() as u64) as usize;
    let (mut solid, symmetries) = match family {
        NovelFamily::Superquadric => superquadric(&mut rng),
        NovelFamily::StarPrism => star_prism(&mut rng),
        NovelFamily::Torus => torus(&mut rng, variant.is_multiple_of(2)),
        NovelFamily::Bracket => bracket(&mut rng, variant % 3),
        NovelFamily::TwistedPrism => twisted_prism(&mut rng),
        NovelFamily::HoledFrustum => holed_frustum(&mut rng, variant.is_multiple_of(2)),
    };
    // Every symmetry above is about an axis through the origin, which uniform scaling keeps.
    let (lo, hi) = solid.bounds();
    let diagonal = (hi - lo).norm();
    if diagonal > DIAGONAL_M.1 {
        solid.scale(DIAGONAL_M.1 / diagonal);
    } else if diagonal < DIAGONAL_M.0 {
        solid.scale(DIAGONAL_M.0 / diagonal);
    }
    let mut geometry = solid.into_builder(CREASE_DEG);
    let shift = geometry.center_on_bounding_box().cast::<f64>();
    let symmetries = symmetries.into_iter().map(|s| shifted(s, &shift)).collect();
    let texture = texture::paint(&mut rng);
    NovelObject {
        family,
        seed,
        name: novel_name(family, seed),
        geometry,
        texture,
        symmetries,
    }
}

/// The symmetry `s` after every point moved by `shift`.
fn shifted(s: Symmetry, shift: &Vector3<f64>) -> Symmetry {
    match s {
        Symmetry::Discrete(t) => {
            let to = Isometry3::from_parts(Translation3::from(*shift), UnitQuaternion::identity());
            Symmetry::Discrete(to * t * to.inverse())
        }
        Symmetry::Continuous { axis, offset } => Symmetry::Continuous {
            axis,
            offset: offset + shift,
        },
    }
}

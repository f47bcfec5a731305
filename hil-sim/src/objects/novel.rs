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

use super::builder::{MeshBuilder, UvRect};
use super::model::ObjectModel;
use super::solid::{Corner, Solid};
use super::texture::{Canvas, Colour, TEXTURE_SIZE, checker, fbm, mix, shade, stripe, text_lines};
use crate::rng::SeedRng;
use image::RgbImage;
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use scene::mesh::Symmetry;
use std::f64::consts::{FRAC_PI_4, PI, TAU};

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

/// Segments around every round outline (torus tube, round frustum); the major circle of a full torus has 64.
const AROUND: usize = 48;

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
    let texture = paint(&mut rng);
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

/// A turn by `angle` about `axis` through the origin.
fn turn(axis: Vector3<f64>, angle: f64) -> Symmetry {
    Symmetry::Discrete(Isometry3::from_parts(
        Translation3::identity(),
        UnitQuaternion::from_scaled_axis(axis.normalize() * angle),
    ))
}

/// The `n - 1` turns by multiples of `2 pi / n` about z.
fn turns_about_z(n: usize) -> Vec<Symmetry> {
    (1..n)
        .map(|k| turn(Vector3::z(), TAU * k as f64 / n as f64))
        .collect()
}

/// Region `k` (0 to 5) of the atlas: three columns, two rows.
fn tile(k: usize) -> UvRect {
    let (c, r) = ((k % 3) as f32, (k / 3 % 2) as f32);
    UvRect::new(c / 3.0, r / 2.0, (c + 1.0) / 3.0, (r + 1.0) / 2.0)
}

fn corner(p: Point3<f32>, uv: [f32; 2]) -> Corner {
    Corner { p, uv }
}

fn point(x: f64, y: f64, z: f64) -> Point3<f32> {
    Point3::new(x as f32, y as f32, z as f32)
}

/// A whole number in `lo..=hi`.
fn pick(rng: &mut SeedRng, lo: usize, hi: usize) -> usize {
    (lo + (rng.uniform() * (hi - lo + 1) as f64) as usize).min(hi)
}

/// A random sign.
fn sign(rng: &mut SeedRng) -> f64 {
    if rng.uniform() < 0.5 { -1.0 } else { 1.0 }
}

/// Cube coordinate `i` of `0..=n`: equal-angle spacing from exactly -1 to exactly 1, antisymmetric, so that faces
/// meeting at an edge compute the same points.
fn cube_coord(i: usize, n: usize) -> f64 {
    let x = 2 * i as i64 - n as i64;
    let a = x.unsigned_abs() as f64 / n as f64;
    let v = if a >= 1.0 { 1.0 } else { (a * FRAC_PI_4).tan() };
    if x < 0 { -v } else { v }
}

/// A superellipsoid `(|x/a|^(2/e2) + |y/b|^(2/e2))^(e2/e1) + |z/c|^(2/e1) = 1`, meshed by projecting a cube's
/// faces onto it (no poles); each face in its own atlas region. Symmetries: half turns about x, y and z (the
/// semi-axes differ by at least 20 %, so no other).
fn superquadric(rng: &mut SeedRng) -> (Solid, Vec<Symmetry>) {
    let big = rng.range(0.05, 0.11);
    let mid = big / rng.range(1.25, 2.0);
    let small = (mid / rng.range(1.2, 1.8)).max(0.012);
    let order = pick(rng, 0, 5);
    let axes = [
        [big, mid, small],
        [big, small, mid],
        [mid, big, small],
        [mid, small, big],
        [small, big, mid],
        [small, mid, big],
    ][order];
    let e1 = rng.range(0.3, 1.6);
    let mut e2 = rng.range(0.3, 1.6);
    if e1 < 0.6 && e2 < 0.6 {
        e2 += 0.6; // not merely a rounded box
    }
    let on_surface = |d: [f64; 3]| {
        let [x, y, z] = d.map(f64::abs);
        let f = (x.powf(2.0 / e2) + y.powf(2.0 / e2)).powf(e2 / e1) + z.powf(2.0 / e1);
        let s = f.powf(-e1 / 2.0);
        point(axes[0] * s * d[0], axes[1] * s * d[1], axes[2] * s * d[2])
    };
    // (outward axis, u axis, v axis) with u x v = outward: component index and sign.
    let faces: [[(usize, f64); 3]; 6] = [
        [(0, 1.0), (1, 1.0), (2, 1.0)],
        [(0, -1.0), (2, 1.0), (1, 1.0)],
        [(1, 1.0), (2, 1.0), (0, 1.0)],
        [(1, -1.0), (0, 1.0), (2, 1.0)],
        [(2, 1.0), (0, 1.0), (1, 1.0)],
        [(2, -1.0), (1, 1.0), (0, 1.0)],
    ];
    let n = 20;
    let mut solid = Solid::default();
    for (k, [(ni, ns), (ui, us), (vi, vs)]) in faces.into_iter().enumerate() {
        let uv = tile(k);
        solid.grid(n + 1, n + 1, |i, j| {
            let mut d = [0.0; 3];
            d[ni] = ns;
            d[ui] = us * cube_coord(i, n);
            d[vi] = vs * cube_coord(j, n);
            corner(
                on_surface(d),
                uv.map(i as f32 / n as f32, j as f32 / n as f32),
            )
        });
    }
    let symmetries = vec![
        turn(Vector3::x(), PI),
        turn(Vector3::y(), PI),
        turn(Vector3::z(), PI),
    ];
    (solid, symmetries)
}

/// One cross-section of an extrusion: the profile scaled by `scale` about its kernel point, turned by `twist`
/// (radians) about it, at height `z`.
#[derive(Debug, Clone, Copy)]
struct Ring {
    z: f64,
    scale: f64,
    twist: f64,
}

/// A prism over `profile` (a simple polygon, counter-clockwise seen from +z, star-shaped about `kernel`: every
/// vertex seen from it) through `rings` (bottom to top), closed by fans from the kernel point. Sides in atlas
/// region 0 (`u` along the outline, `v` up), bottom and top in regions 1 and 2.
fn extrude(profile: &[[f64; 2]], kernel: [f64; 2], rings: &[Ring]) -> Solid {
    let m = profile.len();
    let at: Vec<Vec<Point3<f32>>> = rings
        .iter()
        .map(|r| {
            let (s, c) = r.twist.sin_cos();
            profile
                .iter()
                .map(|v| {
                    let (x, y) = ((v[0] - kernel[0]) * r.scale, (v[1] - kernel[1]) * r.scale);
                    point(kernel[0] + c * x - s * y, kernel[1] + s * x + c * y, r.z)
                })
                .collect()
        })
        .collect();
    let mut along = vec![0.0f64; m + 1];
    for j in 0..m {
        let (a, b) = (profile[j], profile[(j + 1) % m]);
        along[j + 1] = along[j] + (b[0] - a[0]).hypot(b[1] - a[1]);
    }
    let total = along[m].max(1e-12);
    let (z0, z1) = (rings[0].z, rings[rings.len() - 1].z);
    let side = tile(0);
    let mut solid = Solid::default();
    solid.grid(m + 1, rings.len(), |j, k| {
        corner(
            at[k][j % m],
            side.map(
                (along[j] / total) as f32,
                ((rings[k].z - z0) / (z1 - z0)) as f32,
            ),
        )
    });
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for v in profile {
        for a in 0..2 {
            lo[a] = lo[a].min(v[a]);
            hi[a] = hi[a].max(v[a]);
        }
    }
    let span = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1e-12);
    for (end, region) in [(0, tile(1)), (rings.len() - 1, tile(2))] {
        let cap = |p: Point3<f32>| {
            corner(
                p,
                region.map(
                    ((f64::from(p.x) - lo[0]) / span) as f32,
                    ((f64::from(p.y) - lo[1]) / span) as f32,
                ),
            )
        };
        let mut ring: Vec<Corner> = (0..=m).map(|j| cap(at[end][j % m])).collect();
        if end == 0 {
            ring.reverse(); // the bottom faces -z
        }
        solid.fan(cap(point(kernel[0], kernel[1], rings[end].z)), &ring);
    }
    solid
}

/// The largest distance of a profile vertex from the kernel point.
fn reach(profile: &[[f64; 2]], kernel: [f64; 2]) -> f64 {
    profile
        .iter()
        .map(|v| (v[0] - kernel[0]).hypot(v[1] - kernel[1]))
        .fold(0.0, f64::max)
}

/// Straight-sided rings with a bevel of `bevel` metres (height) at both ends that insets the outline by up to
/// `inset` metres.
fn bevelled(height: f64, bevel: f64, inset: f64, reach: f64) -> Vec<Ring> {
    let k = 1.0 - inset / reach.max(1e-9);
    let h = height / 2.0;
    [(-h, k), (-h + bevel, 1.0), (h - bevel, 1.0), (h, k)]
        .into_iter()
        .map(|(z, scale)| Ring {
            z,
            scale,
            twist: 0.0,
        })
        .collect()
}

/// A bevelled prism over a regular star of `n` points (tips on the x axis and every `2 pi / n`). Symmetries: the
/// dihedral group, turns by `2 pi k / n` about z and half turns about the `n` in-plane axes through tips and notches.
fn star_prism(rng: &mut SeedRng) -> (Solid, Vec<Symmetry>) {
    let n = pick(rng, 4, 8);
    let outer = rng.range(0.045, 0.1);
    let inner = outer * rng.range(0.4, 0.7);
    let thickness = rng.range(0.02, 0.05);
    let bevel = thickness * rng.range(0.12, 0.25);
    let inset = rng.range(0.003, 0.007);
    let profile: Vec<[f64; 2]> = (0..2 * n)
        .map(|k| {
            let a = PI * k as f64 / n as f64;
            let r = if k % 2 == 0 { outer } else { inner };
            [r * a.cos(), r * a.sin()]
        })
        .collect();
    let rings = bevelled(thickness, bevel, inset, outer);
    let mut symmetries = turns_about_z(n);
    for m in 0..n {
        let a = PI * m as f64 / n as f64;
        symmetries.push(turn(Vector3::new(a.cos(), a.sin(), 0.0), PI));
    }
    (extrude(&profile, [0.0, 0.0], &rings), symmetries)
}

/// A torus of major radius `R`, tube semi-axes `r1` (in the plane) and `r2` (along z), `whole` or a segment of 200
/// to 300 degrees symmetric about +x with flat ends. Tube in atlas region 0, ends in 1 and 2. Symmetries: any turn
/// about z and a half turn about x (whole); the half turn about x (segment).
fn torus(rng: &mut SeedRng, whole: bool) -> (Solid, Vec<Symmetry>) {
    let big = rng.range(0.04, 0.085);
    let r1 = rng.range(0.012, 0.026);
    let r2 = (r1 * rng.range(0.7, 1.4)).max(0.011);
    let sweep = if whole {
        TAU
    } else {
        rng.range(200.0, 300.0).to_radians()
    };
    let (major, minor) = (if whole { 64 } else { 48 }, AROUND / 2);
    let angle = |i: usize| {
        if whole {
            TAU * (i % major) as f64 / major as f64
        } else {
            -sweep / 2.0 + sweep * i as f64 / major as f64
        }
    };
    let at = |i: usize, j: usize| {
        let (phi, theta) = (angle(i), TAU * (j % minor) as f64 / minor as f64);
        let r = big + r1 * theta.cos();
        point(r * phi.cos(), r * phi.sin(), r2 * theta.sin())
    };
    let uv = tile(0);
    let mut solid = Solid::default();
    solid.grid(major + 1, minor + 1, |i, j| {
        corner(
            at(i, j),
            uv.map(i as f32 / major as f32, j as f32 / minor as f32),
        )
    });
    let mut symmetries = vec![turn(Vector3::x(), PI)];
    if whole {
        symmetries.push(Symmetry::Continuous {
            axis: Vector3::z_axis(),
            offset: Point3::origin(),
        });
    } else {
        for (i, region) in [(0, tile(1)), (major, tile(2))] {
            let cap = |j: usize| {
                let theta = TAU * j as f64 / minor as f64;
                corner(
                    at(i, j),
                    region.map(
                        (0.5 + 0.5 * theta.cos()) as f32,
                        (0.5 + 0.5 * theta.sin()) as f32,
                    ),
                )
            };
            let mut ring: Vec<Corner> = (0..=minor).map(cap).collect();
            if i == major {
                ring.reverse(); // the far end faces the other way
            }
            let phi = angle(i);
            let centre = corner(
                point(big * phi.cos(), big * phi.sin(), 0.0),
                region.map(0.5, 0.5),
            );
            solid.fan(centre, &ring);
        }
    }
    (solid, symmetries)
}

/// An L, T or cross of bars (`shape` 0, 1, 2; never symmetric: unequal arms, an off-centre stem, unequal widths)
/// extruded 2.5 to 6 cm and bevelled. No symmetries.
fn bracket(rng: &mut SeedRng, shape: usize) -> (Solid, Vec<Symmetry>) {
    let depth = rng.range(0.025, 0.06);
    let w1 = rng.range(0.025, 0.045);
    // Widths differ by at least 8 mm, so no diagonal mirror maps one bar onto the other.
    let w2 = if rng.uniform() < 0.5 {
        w1 + rng.range(0.008, 0.015)
    } else {
        (w1 - rng.range(0.008, 0.012)).max(0.017)
    };
    let (profile, kernel) = match shape {
        0 => {
            let a = rng.range(0.1, 0.2);
            let b = a * rng.range(0.45, 0.8); // arms differ by at least 2 cm
            (
                vec![[0.0, 0.0], [a, 0.0], [a, w1], [w2, w1], [w2, b], [0.0, b]],
                [w2 / 2.0, w1 / 2.0],
            )
        }
        1 => {
            let a = rng.range(0.11, 0.2);
            let b = rng.range(0.07, 0.15);
            let room = a / 2.0 - w2 / 2.0 - 0.005;
            let s = sign(rng) * room * rng.range(0.25, 0.6);
            (
                vec![
                    [s - w2 / 2.0, 0.0],
                    [s + w2 / 2.0, 0.0],
                    [s + w2 / 2.0, b - w1],
                    [a / 2.0, b - w1],
                    [a / 2.0, b],
                    [-a / 2.0, b],
                    [-a / 2.0, b - w1],
                    [s - w2 / 2.0, b - w1],
                ],
                [s, b - w1 / 2.0],
            )
        }
        _ => {
            // Arms from the crossing: each pair differs by at least 1.5 cm.
            let arm = |rng: &mut SeedRng, w: f64| {
                let short = w / 2.0 + rng.range(0.02, 0.04);
                let long = short + rng.range(0.015, 0.05);
                if rng.uniform() < 0.5 {
                    (short, long)
                } else {
                    (long, short)
                }
            };
            let (a1, a2) = arm(rng, w2);
            let (b1, b2) = arm(rng, w1);
            let (h1, h2) = (w1 / 2.0, w2 / 2.0);
            (
                vec![
                    [-h2, -b1],
                    [h2, -b1],
                    [h2, -h1],
                    [a2, -h1],
                    [a2, h1],
                    [h2, h1],
                    [h2, b2],
                    [-h2, b2],
                    [-h2, h1],
                    [-a1, h1],
                    [-a1, -h1],
                    [-h2, -h1],
                ],
                [0.0, 0.0],
            )
        }
    };
    let bevel = depth * rng.range(0.1, 0.18);
    let rings = bevelled(
        depth,
        bevel,
        rng.range(0.002, 0.004),
        reach(&profile, kernel),
    );
    (extrude(&profile, kernel, &rings), vec![])
}

/// An irregular polygon of 3 to 7 corners (angles and radii jittered), each side split in three, extruded 9 to
/// 20 cm while turning by 45 to 150 degrees and shrinking to 50-95 %, with bevelled ends. No symmetries.
fn twisted_prism(rng: &mut SeedRng) -> (Solid, Vec<Symmetry>) {
    let corners = pick(rng, 3, 7);
    let radius = rng.range(0.025, 0.05);
    let length = rng.range(0.09, 0.2);
    let twist = sign(rng) * rng.range(45.0, 150.0).to_radians();
    let taper = rng.range(0.5, 0.95);
    let vertices: Vec<[f64; 2]> = (0..corners)
        .map(|c| {
            // Gaps between corner angles stay below pi, so the outline is star-shaped about the origin.
            let a = TAU * (c as f64 + rng.range(-0.2, 0.2)) / corners as f64;
            let r = radius * rng.range(0.65, 1.0);
            [r * a.cos(), r * a.sin()]
        })
        .collect();
    let split = 3;
    let profile: Vec<[f64; 2]> = (0..corners * split)
        .map(|k| {
            let (a, b) = (vertices[k / split], vertices[(k / split + 1) % corners]);
            let f = (k % split) as f64 / split as f64;
            [a[0] + (b[0] - a[0]) * f, a[1] + (b[1] - a[1]) * f]
        })
        .collect();
    let bevel = rng.range(0.004, 0.008);
    let k_end = 1.0 - rng.range(0.003, 0.006) / radius;
    let steps = 20;
    let h = length / 2.0;
    let mut rings = vec![Ring {
        z: -h,
        scale: k_end,
        twist: 0.0,
    }];
    for s in 0..=steps {
        let f = s as f64 / steps as f64;
        rings.push(Ring {
            z: -h + bevel + (length - 2.0 * bevel) * f,
            scale: 1.0 + (taper - 1.0) * f,
            twist: twist * f,
        });
    }
    rings.push(Ring {
        z: h,
        scale: taper * k_end,
        twist,
    });
    (extrude(&profile, [0.0, 0.0], &rings), vec![])
}

/// A frustum, `round` or 5-, 6- or 8-sided, 5 to 14 cm tall, its top 45-80 % of its base, with an axial round
/// hole through it (walls at least 8 mm). Outside, top, hole and bottom in atlas regions 0 to 3. Symmetries: any
/// turn about z (round) or the turns by `2 pi k / sides`.
fn holed_frustum(rng: &mut SeedRng, round: bool) -> (Solid, Vec<Symmetry>) {
    let sides = if round { 0 } else { [5, 6, 8][pick(rng, 0, 2)] };
    let bottom = rng.range(0.035, 0.08);
    let top = bottom * rng.range(0.45, 0.8);
    let height = rng.range(0.05, 0.14);
    let hole = (top * rng.range(0.3, 0.6)).min(top - 0.008).max(0.006);
    let per_side = if sides == 0 {
        1
    } else {
        AROUND.div_ceil(sides)
    };
    let m = if sides == 0 { AROUND } else { sides * per_side };
    let outline = |j: usize, r: f64| -> [f64; 2] {
        let j = j % m;
        if sides == 0 {
            let a = TAU * j as f64 / m as f64;
            return [r * a.cos(), r * a.sin()];
        }
        let (s, f) = (j / per_side, (j % per_side) as f64 / per_side as f64);
        let (a0, a1) = (
            TAU * s as f64 / sides as f64,
            TAU * (s + 1) as f64 / sides as f64,
        );
        [
            r * (a0.cos() + (a1.cos() - a0.cos()) * f),
            r * (a0.sin() + (a1.sin() - a0.sin()) * f),
        ]
    };
    let circle = |j: usize, r: f64| {
        let a = TAU * (j % m) as f64 / m as f64;
        [r * a.cos(), r * a.sin()]
    };
    let h = height / 2.0;
    let ring = |pts: &dyn Fn(usize) -> [f64; 2], z: f64| -> Vec<Point3<f32>> {
        (0..m)
            .map(|j| {
                let p = pts(j);
                point(p[0], p[1], z)
            })
            .collect()
    };
    let outer_bottom = ring(&|j| outline(j, bottom), -h);
    let outer_top = ring(&|j| outline(j, top), h);
    let inner_top = ring(&|j| circle(j, hole), h);
    let inner_bottom = ring(&|j| circle(j, hole), -h);
    let mut solid = Solid::default();
    // Each band: from one ring to the next, outside on the side of (along the rings) x (across).
    let bands = [
        (&outer_bottom, &outer_top),
        (&outer_top, &inner_top),
        (&inner_top, &inner_bottom),
        (&inner_bottom, &outer_bottom),
    ];
    for (k, (from, to)) in bands.into_iter().enumerate() {
        let uv = tile(k);
        solid.grid(m + 1, 2, |j, across| {
            let p = if across == 0 { from[j % m] } else { to[j % m] };
            corner(p, uv.map(j as f32 / m as f32, across as f32))
        });
    }
    let symmetries = if sides == 0 {
        vec![Symmetry::Continuous {
            axis: Vector3::z_axis(),
            offset: Point3::origin(),
        }]
    } else {
        turns_about_z(sides)
    };
    (solid, symmetries)
}

/// Saturated and neutral paint colours.
const PALETTE: [Colour; 12] = [
    [0.85, 0.15, 0.12],
    [0.95, 0.6, 0.1],
    [0.95, 0.85, 0.2],
    [0.2, 0.6, 0.25],
    [0.1, 0.45, 0.75],
    [0.45, 0.2, 0.65],
    [0.9, 0.4, 0.6],
    [0.1, 0.65, 0.65],
    [0.92, 0.9, 0.85],
    [0.12, 0.12, 0.14],
    [0.55, 0.35, 0.2],
    [0.55, 0.58, 0.62],
];

fn luminance(c: Colour) -> f32 {
    0.3 * c[0] + 0.59 * c[1] + 0.11 * c[2]
}

/// The texture atlas: two contrasting colours (the accent blended 55-85 % over the base) in one of four patterns
/// (stripes at an angle, checks, blobs, rings), grain over everything, and printed-label blocks on two regions.
fn paint(rng: &mut SeedRng) -> RgbImage {
    let base = PALETTE[pick(rng, 0, PALETTE.len() - 1)];
    let mut accent = PALETTE[pick(rng, 0, PALETTE.len() - 1)];
    if (luminance(accent) - luminance(base)).abs() < 0.25 {
        accent = if luminance(base) > 0.5 {
            shade(accent, 0.3)
        } else {
            mix(accent, [1.0; 3], 0.7)
        };
    }
    let ink: Colour = if luminance(base) > 0.45 {
        [0.06, 0.06, 0.08]
    } else {
        [0.95, 0.95, 0.9]
    };
    let pattern = pick(rng, 0, 3);
    // How far the pattern goes from the base colour to the accent: full black-on-white stripes would fire several
    // times the events of the library's textures.
    let strength = rng.range(0.55, 0.85) as f32;
    let period = rng.range(0.07, 0.16) as f32;
    let (sa, ca) = (rng.range(0.0, PI) as f32).sin_cos();
    let cells = pick(rng, 4, 9) as f32;
    let blobs = rng.range(5.0, 10.0) as f32;
    let noise = (rng.uniform() * f64::from(u32::MAX)) as u32;
    let mut canvas = Canvas::new(TEXTURE_SIZE);
    for k in 0..6 {
        let region = tile(k);
        let n = noise.wrapping_add(k as u32 * 7919);
        canvas.paint(&region, |s, t| {
            let m = match pattern {
                0 => stripe(s * ca + t * sa, period, 0.5),
                1 => checker(s, t, cells),
                2 => {
                    if fbm(s * blobs, t * blobs, n ^ 0x5a5a, 3) > 0.5 {
                        1.0
                    } else {
                        0.0
                    }
                }
                _ => stripe(((s - 0.5).powi(2) + (t - 0.5).powi(2)).sqrt(), period, 0.5),
            };
            let grain = fbm(s * 24.0, t * 24.0, n, 3);
            shade(mix(base, accent, m * strength), 0.75 + 0.5 * grain)
        });
    }
    for k in [0, 2] {
        let s0 = rng.range(0.05, 0.3) as f32;
        let t0 = rng.range(0.1, 0.5) as f32;
        let area = [s0, t0, s0 + 0.5, t0 + 0.3];
        let rects = text_lines(rng.range(0.0, 1e9) as u64, area, 3, 0.06);
        canvas.blocks(&tile(k), &rects, ink);
    }
    canvas.into_image()
}

#[cfg(test)]
mod tests {
    use super::super::solid::checks;
    use super::*;
    use crate::objects::{render_preview, write_object};
    use scene::mesh::{MeshLoadOptions, load_obj};
    use std::collections::HashMap;

    /// Per family, each variant at least once (the variant turns with `seed / 6`).
    const SEEDS: [u64; 5] = [1, 7, 13, 7003, 123_456];

    fn positions(o: &NovelObject) -> Vec<Point3<f64>> {
        let mut seen = std::collections::HashSet::new();
        o.geometry
            .positions
            .iter()
            .filter(|p| seen.insert(super::super::solid::position_key(p)))
            .map(|p| p.cast::<f64>())
            .collect()
    }

    #[test]
    fn every_family_makes_closed_outward_meshes_of_graspable_size() {
        for family in NovelFamily::ALL {
            for seed in SEEDS {
                let o = generate(family, seed);
                let what = format!("{} ({} triangles)", o.name, o.geometry.triangles.len());
                checks::closed(&o.geometry).unwrap_or_else(|e| panic!("{what}: not closed: {e}"));
                let volume = checks::signed_volume(&o.geometry);
                assert!(volume > 2e-5, "{what}: volume {volume} m^3");
                let mesh = o.to_mesh().unwrap();
                let d = mesh.diameter();
                assert!((0.05..=0.25).contains(&d), "{what}: diameter {d}");
                let b = mesh.aabb();
                let size = b.max - b.min;
                assert!(size.max() >= 0.05, "{what}: {size:?}");
                assert!(size.min() >= 0.012, "{what}: too thin {size:?}");
                assert!(b.center().coords.norm() < 1e-6, "{what}: not centred");
                assert!((40..20_000).contains(&o.geometry.triangles.len()), "{what}");
                // Every vertex normal is unit and on the outer side of the faces it belongs to.
                for t in &o.geometry.triangles {
                    let [a, b, c] = t.map(|i| o.geometry.positions[i as usize]);
                    let face = (b - a).cross(&(c - a));
                    for &i in t {
                        let n = o.geometry.normals[i as usize];
                        assert!((n.norm() - 1.0).abs() < 1e-4, "{what}");
                        assert!(face.dot(&n) >= 0.0, "{what}: normal against its face");
                    }
                }
                assert_eq!(o.texture.dimensions(), (TEXTURE_SIZE, TEXTURE_SIZE));
                assert_eq!(parse_spec(&o.name), Some((family, seed)), "{what}");
            }
        }
    }

    #[test]
    fn the_same_seed_gives_the_same_files_byte_for_byte_and_they_load_back() {
        for family in NovelFamily::ALL {
            let dirs = [tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap()];
            let files: Vec<_> = dirs
                .iter()
                .map(|d| write_object(&generate(family, 42), d.path()).unwrap())
                .collect();
            let loaded = load_obj(&files[0].obj, &MeshLoadOptions::default()).unwrap();
            let made = generate(family, 42).to_mesh().unwrap();
            assert_eq!(loaded.mesh.positions(), made.positions(), "{family:?}");
            assert_eq!(loaded.mesh.triangles(), made.triangles(), "{family:?}");
            for (a, b) in [
                (&files[0].obj, &files[1].obj),
                (&files[0].mtl, &files[1].mtl),
                (&files[0].texture, &files[1].texture),
            ] {
                assert_eq!(
                    std::fs::read(a).unwrap(),
                    std::fs::read(b).unwrap(),
                    "{family:?}"
                );
            }
        }
    }

    #[test]
    fn different_seeds_give_different_shapes() {
        for family in NovelFamily::ALL {
            let sizes: Vec<Vector3<f32>> = (0..4)
                .map(|seed| {
                    let g = generate(family, seed).geometry;
                    let (lo, hi) = g.positions.iter().fold(
                        (Vector3::repeat(f32::MAX), Vector3::repeat(f32::MIN)),
                        |(lo, hi), p| (lo.inf(&p.coords), hi.sup(&p.coords)),
                    );
                    hi - lo
                })
                .collect();
            for i in 0..sizes.len() {
                for j in 0..i {
                    assert!(
                        (sizes[i] - sizes[j]).norm() > 2e-3,
                        "{family:?} seeds {i} and {j}: {:?} {:?}",
                        sizes[i],
                        sizes[j]
                    );
                }
            }
        }
    }

    /// Largest distance from a transformed vertex to the nearest vertex (2 mm grid; farther counts as 1 m).
    fn mismatch(points: &[Point3<f64>], t: &Isometry3<f64>) -> f64 {
        let cell = 0.002;
        let key = |p: &Point3<f64>| [p.x, p.y, p.z].map(|c| (c / cell).floor() as i64);
        let mut grid: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
        for (i, p) in points.iter().enumerate() {
            grid.entry(key(p)).or_default().push(i);
        }
        let mut worst: f64 = 0.0;
        for p in points {
            let q = t * p;
            let k = key(&q);
            let mut best = 1.0f64;
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        for &i in grid
                            .get(&[k[0] + dx, k[1] + dy, k[2] + dz])
                            .into_iter()
                            .flatten()
                        {
                            best = best.min((points[i] - q).norm());
                        }
                    }
                }
            }
            worst = worst.max(best);
        }
        worst
    }

    fn same(a: &Isometry3<f64>, b: &Isometry3<f64>) -> bool {
        [
            Point3::origin(),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
            Point3::new(0.0, 0.0, 1.0),
        ]
        .iter()
        .all(|p| (a * p - b * p).norm() < 1e-6)
    }

    #[test]
    fn declared_symmetries_hold_and_no_simple_turn_is_left_out() {
        for family in NovelFamily::ALL {
            for seed in SEEDS {
                let o = generate(family, seed);
                let points = positions(&o);
                let mut group = vec![Isometry3::identity()];
                let mut continuous = None;
                for s in &o.symmetries {
                    match s {
                        Symmetry::Discrete(t) => {
                            let m = mismatch(&points, t);
                            assert!(m < 5e-5, "{}: {t:?} off by {m}", o.name);
                            group.push(*t);
                        }
                        Symmetry::Continuous { axis, offset } => {
                            for k in [1.0, 3.0] {
                                let r = UnitQuaternion::from_axis_angle(axis, TAU * k / 16.0);
                                let t = Isometry3::from_parts(Translation3::from(offset.coords), r)
                                    * Isometry3::from_parts(
                                        Translation3::from(-offset.coords),
                                        UnitQuaternion::identity(),
                                    );
                                let m = mismatch(&points, &t);
                                assert!(m < 5e-5, "{}: continuous off by {m}", o.name);
                            }
                            continuous = Some((*axis, *offset));
                        }
                    }
                }
                // The declared turns form a group (closed under composition).
                for a in &group {
                    for b in &group {
                        assert!(
                            group.iter().any(|g| same(g, &(a * b))),
                            "{}: declared symmetries are not a group",
                            o.name
                        );
                    }
                }
                let c = checks::volume_centroid(&o.geometry);
                let about_c = |r: UnitQuaternion<f64>| {
                    Isometry3::from_parts(Translation3::from(c.coords), r)
                        * Isometry3::from_parts(
                            Translation3::from(-c.coords),
                            UnitQuaternion::identity(),
                        )
                };
                for axis in [Vector3::x_axis(), Vector3::y_axis(), Vector3::z_axis()] {
                    for k in 2..=8 {
                        let t = about_c(UnitQuaternion::from_axis_angle(&axis, TAU / k as f64));
                        if mismatch(&points, &t) > 5e-4 {
                            continue;
                        }
                        let declared = group.iter().any(|g| same(g, &t))
                            || continuous.is_some_and(|(a, off)| {
                                group.iter().any(|g| {
                                    let rest = g.inverse() * t;
                                    let on_axis = off + a.into_inner() * 0.1;
                                    (rest * off - off).norm() < 1e-6
                                        && (rest * on_axis - on_axis).norm() < 1e-6
                                })
                            });
                        assert!(
                            declared,
                            "{}: a turn by 360/{k} degrees about {:?} maps it onto itself but is not declared",
                            o.name,
                            axis.into_inner()
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn textures_make_contrast_inside_the_silhouette() {
        for family in NovelFamily::ALL {
            let o = generate(family, 5);
            let img = render_preview(&o, 96).unwrap();
            let mut lit: Vec<u8> = img.pixels().map(|p| p.0[0]).filter(|&v| v > 0).collect();
            assert!(
                lit.len() > 96 * 96 / 10,
                "{}: {} lit pixels",
                o.name,
                lit.len()
            );
            lit.sort_unstable();
            let (p10, p90) = (lit[lit.len() / 10], lit[lit.len() * 9 / 10]);
            assert!(p90 - p10 >= 30, "{}: flat texture ({p10}..{p90})", o.name);
        }
    }

    #[test]
    fn names_and_specs_read_back() {
        for family in NovelFamily::ALL {
            for seed in [0, 9, 7001, u64::MAX] {
                let name = novel_name(family, seed);
                assert!(name.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'_'));
                assert_eq!(parse_spec(&name), Some((family, seed)));
            }
        }
        let families: std::collections::HashSet<_> =
            (7000..7006).map(NovelFamily::for_seed).collect();
        assert_eq!(families.len(), NovelFamily::ALL.len());
        assert_eq!(
            parse_spec("novel:7001"),
            Some((NovelFamily::for_seed(7001), 7001))
        );
        for bad in [
            "novel:",
            "novel:x",
            "novel:-1",
            "novel:1:2",
            "novel_cube_3",
            "novel_torus_",
            "novel_torus_-1",
            "novel_torus_17x",
            "novel_torus_017",
            "novel_torus",
            "torus_17",
            "mug",
        ] {
            assert_eq!(parse_spec(bad), None, "{bad}");
        }
    }
}

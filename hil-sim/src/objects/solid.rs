//! Closed solids assembled from parametric grids and fans whose winding is known by construction, welded by
//! position: each generator computes a point shared by two patches once and reuses it, so edges meet exactly and the
//! surface is watertight. Normals come from the faces (smooth across edges flatter than a crease angle, sharp across
//! the others), so the builder's vertices carry the same shading a modelling tool's auto-smooth would give.

use super::builder::MeshBuilder;
use nalgebra::{Point3, Vector3};
use std::collections::HashMap;

/// A triangle corner: position (metres, object frame) and texture coordinate in the atlas.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Corner {
    /// Position.
    pub p: Point3<f32>,
    /// Atlas coordinate.
    pub uv: [f32; 2],
}

/// A closed surface under construction: triangles counter-clockwise seen from outside.
#[derive(Debug, Clone, Default)]
pub(crate) struct Solid {
    tris: Vec<[Corner; 3]>,
}

/// The exact position of a point, as a hash key (`-0.0` and `0.0` are the same point).
pub(crate) fn position_key(p: &Point3<f32>) -> [u32; 3] {
    [p.x, p.y, p.z].map(|c| (c + 0.0).to_bits())
}

impl Solid {
    /// Adds a triangle (counter-clockwise seen from outside), unless two of its corners are the same point (the
    /// collapsed side of a quad at a pole or an apex, which the neighbouring triangles close).
    pub fn tri(&mut self, a: Corner, b: Corner, c: Corner) {
        let [ka, kb, kc] = [a, b, c].map(|x| position_key(&x.p));
        if ka == kb || kb == kc || kc == ka {
            return;
        }
        self.tris.push([a, b, c]);
    }

    /// A grid patch of `rows x cols` corners: `corner(i, j)` for `i < rows`, `j < cols`, with the surface's outside
    /// on the side of (direction of growing `i`) x (direction of growing `j`). A closed loop repeats its first row
    /// or column as its last (same positions, other texture coordinates).
    pub fn grid(&mut self, rows: usize, cols: usize, corner: impl Fn(usize, usize) -> Corner) {
        if rows < 2 || cols < 2 {
            return;
        }
        let pts: Vec<Corner> = (0..rows)
            .flat_map(|i| (0..cols).map(move |j| (i, j)))
            .map(|(i, j)| corner(i, j))
            .collect();
        let at = |i: usize, j: usize| pts[i * cols + j];
        for i in 0..rows - 1 {
            for j in 0..cols - 1 {
                let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                self.tri(a, b, c);
                self.tri(a, c, d);
            }
        }
    }

    /// A fan from `centre` over the open polyline `ring` (`ring.len() >= 2`), counter-clockwise seen from outside
    /// when `ring` runs counter-clockwise around `centre` seen from outside.
    pub fn fan(&mut self, centre: Corner, ring: &[Corner]) {
        for w in ring.windows(2) {
            self.tri(centre, w[0], w[1]);
        }
    }

    /// Number of triangles so far.
    #[cfg(test)]
    pub fn len(&self) -> usize {
        self.tris.len()
    }

    /// Scales every position by `k` about the origin (coincident points stay coincident).
    pub fn scale(&mut self, k: f32) {
        for t in &mut self.tris {
            for c in t.iter_mut() {
                c.p = Point3::from(c.p.coords * k);
            }
        }
    }

    /// The axis-aligned bounds `(min, max)` of every corner.
    pub fn bounds(&self) -> (Point3<f32>, Point3<f32>) {
        let mut lo = Point3::from(Vector3::repeat(f32::INFINITY));
        let mut hi = Point3::from(Vector3::repeat(f32::NEG_INFINITY));
        for c in self.tris.iter().flatten() {
            lo = lo.inf(&c.p);
            hi = hi.sup(&c.p);
        }
        (lo, hi)
    }

    /// The mesh: one vertex per distinct (position, normal, texture coordinate). A corner's normal is the
    /// area-weighted mean of the faces around its position whose normals lie within `crease_deg` of its own face's.
    pub fn into_builder(self, crease_deg: f32) -> MeshBuilder {
        let face_normals: Vec<Vector3<f32>> = self
            .tris
            .iter()
            .map(|[a, b, c]| (b.p - a.p).cross(&(c.p - a.p)))
            .collect();
        let mut around: HashMap<[u32; 3], Vec<usize>> = HashMap::new();
        for (f, t) in self.tris.iter().enumerate() {
            for c in t {
                around.entry(position_key(&c.p)).or_default().push(f);
            }
        }
        let cos_crease = crease_deg.to_radians().cos();
        let mut out = MeshBuilder::default();
        // (position, normal, texture coordinate) bits -> vertex.
        type VertexKey = ([u32; 3], [u32; 3], [u32; 2]);
        let mut index: HashMap<VertexKey, u32> = HashMap::new();
        for (f, t) in self.tris.iter().enumerate() {
            let own = face_normals[f].try_normalize(1e-20);
            let mut tri = [0u32; 3];
            for (k, c) in t.iter().enumerate() {
                let key = position_key(&c.p);
                let mut sum = Vector3::zeros();
                for &g in around.get(&key).map_or(&[][..], Vec::as_slice) {
                    let n = face_normals[g];
                    let close = match (own, n.try_normalize(1e-20)) {
                        (Some(o), Some(u)) => o.dot(&u) >= cos_crease,
                        (None, _) => true,
                        (_, None) => false,
                    };
                    if close {
                        sum += n;
                    }
                }
                let normal = sum.try_normalize(1e-20).or(own).unwrap_or_else(Vector3::z);
                let vkey = (
                    key,
                    [normal.x, normal.y, normal.z].map(f32::to_bits),
                    c.uv.map(f32::to_bits),
                );
                tri[k] = *index.entry(vkey).or_insert_with(|| {
                    out.positions.push(c.p);
                    out.normals.push(normal);
                    out.uvs.push(c.uv);
                    (out.positions.len() - 1) as u32
                });
            }
            out.triangles.push(tri);
        }
        out
    }
}

#[cfg(test)]
pub(crate) mod checks {
    //! Checks on closed meshes shared by the tests of the generators.
    use super::*;

    /// Every undirected edge (vertices welded by exact position) and how often each direction is used.
    fn directed_edges(b: &MeshBuilder) -> HashMap<([u32; 3], [u32; 3]), usize> {
        let mut edges = HashMap::new();
        for t in &b.triangles {
            let k = t.map(|i| position_key(&b.positions[i as usize]));
            for (x, y) in [(k[0], k[1]), (k[1], k[2]), (k[2], k[0])] {
                *edges.entry((x, y)).or_insert(0) += 1;
            }
        }
        edges
    }

    /// `Err` naming the first edge that is not shared by exactly two triangles, once in each direction (a closed,
    /// consistently wound surface).
    pub fn closed(b: &MeshBuilder) -> Result<(), String> {
        let edges = directed_edges(b);
        for (&(x, y), &n) in &edges {
            let back = edges.get(&(y, x)).copied().unwrap_or(0);
            if n != 1 || back != 1 {
                let p = |k: [u32; 3]| k.map(f32::from_bits);
                return Err(format!(
                    "edge {:?} -> {:?} used {n} times, the other way {back} times",
                    p(x),
                    p(y)
                ));
            }
        }
        Ok(())
    }

    /// Signed volume enclosed (positive when the triangles face outwards), cubic metres.
    pub fn signed_volume(b: &MeshBuilder) -> f64 {
        b.triangles
            .iter()
            .map(|t| {
                let [p, q, r] = t.map(|i| b.positions[i as usize].coords.cast::<f64>());
                p.dot(&q.cross(&r)) / 6.0
            })
            .sum()
    }

    /// The centre of the enclosed volume.
    pub fn volume_centroid(b: &MeshBuilder) -> Point3<f64> {
        let (mut sum, mut vol) = (Vector3::zeros(), 0.0);
        for t in &b.triangles {
            let [p, q, r] = t.map(|i| b.positions[i as usize].coords.cast::<f64>());
            let v = p.dot(&q.cross(&r)) / 6.0;
            sum += (p + q + r) / 4.0 * v;
            vol += v;
        }
        Point3::from(sum / vol)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn c(x: f32, y: f32, z: f32) -> Corner {
        Corner {
            p: Point3::new(x, y, z),
            uv: [0.0, 0.0],
        }
    }

    #[test]
    fn a_tetrahedron_of_fans_is_closed_with_outward_faces_and_sharp_normals() {
        let mut s = Solid::default();
        let (o, x, y, z) = (c(0., 0., 0.), c(1., 0., 0.), c(0., 1., 0.), c(0., 0., 1.));
        s.tri(o, y, x);
        s.tri(o, x, z);
        s.tri(o, z, y);
        s.tri(x, y, z);
        s.tri(o, o, x); // collapsed: skipped
        assert_eq!(s.len(), 4);
        let b = s.into_builder(30.0);
        checks::closed(&b).unwrap();
        assert!((checks::signed_volume(&b) - 1.0 / 6.0).abs() < 1e-9);
        // Sharp edges: every corner keeps its face's normal, so 12 vertices.
        assert_eq!(b.positions.len(), 12);
        let b = {
            let mut s = Solid::default();
            s.tri(o, y, x);
            s.tri(o, x, z);
            s.tri(o, z, y);
            s.tri(x, y, z);
            s.into_builder(179.0)
        };
        assert_eq!(
            b.positions.len(),
            4,
            "smooth everywhere: one vertex per point"
        );
    }
}

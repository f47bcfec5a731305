//! Render meshes: a CAD mesh simplified by edge collapses, cheapest first by quadric error (Garland and Heckbert
//! 1997), with every vertex of the input kept within a tolerance of the result. A render costs per triangle
//! drawn, and a CAD export is often tessellated far finer than the tracker's ROI resolves.
//!
//! Each vertex and centre of an input triangle with area belongs to one triangle of the result. A collapse is made
//! only if every such point of the triangles it changes lies within the tolerance of one of the triangles around
//! the merged vertex; they then belong to the nearest of those. The points sample the input's surface, so this
//! also holds the result's faces near it between them (a chord across a curved surface is checked at the points
//! under it); the tests measure how far the surfaces part between the points.
//!
//! The result is geometry only: positions, triangles, crease-angle normals where the input had normals, one
//! default material. Vertices are welded first where their positions round to the same micrometre, so seams where
//! a CAD export duplicates vertices (texture or normal seams) do not open; copies that round apart stay rims,
//! held in place.
//! Collapses keep the surface's topology (the link condition), never flip or flatten a triangle, and leave
//! vertices on non-manifold edges where they are. Boundary edges are held by planes perpendicular to their
//! triangle, so open meshes do not shrink at their rims by more than the tolerance either.

mod distance;
mod normals;
mod quadric;

use super::{Mesh, MeshParts, weld_key};
use distance::point_triangle_distance;
use nalgebra::{Point3, Vector3};
use normals::crease_normals;
use quadric::Quadric;
use std::cmp::Ordering;
use std::collections::{BinaryHeap, HashMap, HashSet};

/// Where the input had vertex normals, the result's are averaged over neighbouring triangles that turn by at most
/// this much (cosine): 40 degrees.
const CREASE_COS: f64 = 0.766;

/// A collapse may leave at most this many triangles around the merged vertex (about 60: it counts the two
/// removed ones), which bounds the work of checking one and keeps hubs from growing.
const MAX_FAN: usize = 64;

/// Meshes reaching farther than this from their origin, metres, are returned unchanged: no tracked object is that
/// large, and welding to the micrometre would overflow.
const MAX_EXTENT_M: f64 = 1e6;

/// Tolerances below this, metres, return the mesh unchanged: welding alone may move a vertex by up to a
/// micrometre, which the reported error does not count.
const MIN_TOLERANCE_M: f64 = 4e-6;

/// A surviving triangle's normal may turn by at most this much (cosine) in one collapse: about 60 degrees.
const MIN_NORMAL_COS: f64 = 0.5;

/// What [`simplify_for_render`] did to a mesh.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Simplification {
    /// Triangles of the input mesh.
    pub triangles_before: usize,
    /// Triangles of the render mesh (equal to `triangles_before` when the input was returned unchanged).
    pub triangles_after: usize,
    /// An upper bound on the distance from a vertex or centre of an input triangle with area to the render mesh,
    /// metres (each point's distance to the render triangle it was assigned to; at most the tolerance).
    pub largest_error_m: f64,
}

/// `mesh` simplified for geometry-only renders, with every vertex and centre of its triangles with area within
/// `tolerance_m` (metres) of the result (degenerate triangles render nothing and are dropped). Returns the input
/// unchanged (normals, texture and all) when the tolerance is below 4 micrometres or NaN, the mesh reaches
/// farther than 1,000 km, or no collapse fits within the tolerance.
pub fn simplify_for_render(mesh: &Mesh, tolerance_m: f64) -> (Mesh, Simplification) {
    let before = mesh.triangles().len();
    let unchanged = || {
        (
            mesh.clone(),
            Simplification {
                triangles_before: before,
                triangles_after: before,
                largest_error_m: 0.0,
            },
        )
    };
    let aabb = mesh.aabb();
    let extent = aabb.min.coords.amax().max(aabb.max.coords.amax());
    if tolerance_m.is_nan() || tolerance_m < MIN_TOLERANCE_M || extent > MAX_EXTENT_M {
        return unchanged();
    }
    let mut collapser = Collapser::new(mesh.positions(), mesh.triangles(), tolerance_m);
    if collapser.run() == 0 {
        return unchanged();
    }
    let largest_error_m = collapser.largest_distance();
    let (positions, triangles) = collapser.into_parts();
    // A mesh shaded smooth stays smooth; one shaded by its facets keeps its facets.
    let parts = if mesh.normals().is_some() {
        crease_normals(&positions, &triangles, CREASE_COS)
    } else {
        MeshParts {
            positions,
            triangles,
            ..MeshParts::default()
        }
    };
    match Mesh::new(mesh.source(), parts) {
        Ok(simplified) => {
            let after = simplified.triangles().len();
            (
                simplified,
                Simplification {
                    triangles_before: before,
                    triangles_after: after,
                    largest_error_m,
                },
            )
        }
        Err(_) => unchanged(),
    }
}

/// One possible collapse: vertex `b` merges into `a`, which moves to `target`. Valid while both vertices still
/// have the versions they had when it was queued.
#[derive(Debug, Clone, Copy)]
struct Candidate {
    cost: f64,
    a: u32,
    b: u32,
    version_a: u32,
    version_b: u32,
    target: Vector3<f64>,
}

impl PartialEq for Candidate {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Candidate {}
impl PartialOrd for Candidate {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Candidate {
    /// Reversed, so that the max-heap pops the cheapest collapse first; ties broken by vertex indices so that the
    /// result does not depend on anything but the input.
    fn cmp(&self, other: &Self) -> Ordering {
        other
            .cost
            .total_cmp(&self.cost)
            .then(other.a.cmp(&self.a))
            .then(other.b.cmp(&self.b))
            .then(other.version_a.cmp(&self.version_a))
            .then(other.version_b.cmp(&self.version_b))
    }
}

/// The mesh being simplified: welded vertices, triangles with liveness, the triangles around each vertex, and
/// which input vertices belong to which triangle.
struct Collapser {
    tolerance: f64,
    input: Vec<Vector3<f64>>,
    face_points: Vec<Vec<u32>>,
    /// Where a checked collapse puts the input vertices of the triangles it changes: (input vertex, triangle).
    moves: Vec<(u32, u32)>,
    position: Vec<Vector3<f64>>,
    quadric: Vec<Quadric>,
    boundary: Vec<bool>,
    locked: Vec<bool>,
    alive: Vec<bool>,
    version: Vec<u32>,
    faces: Vec<[u32; 3]>,
    face_alive: Vec<bool>,
    vertex_faces: Vec<Vec<u32>>,
    queue: BinaryHeap<Candidate>,
}

fn face_normal(p: [Vector3<f64>; 3]) -> Vector3<f64> {
    (p[1] - p[0]).cross(&(p[2] - p[0]))
}

impl Collapser {
    fn new(positions: &[Point3<f32>], triangles: &[[u32; 3]], tolerance: f64) -> Self {
        let mut weld: HashMap<[i64; 3], u32> = HashMap::with_capacity(positions.len());
        let mut position = Vec::with_capacity(positions.len());
        let welded: Vec<u32> = positions
            .iter()
            .map(|p| {
                let key = weld_key([p.x, p.y, p.z]);
                *weld.entry(key).or_insert_with(|| {
                    position.push(p.cast::<f64>().coords);
                    (position.len() - 1) as u32
                })
            })
            .collect();
        let n = position.len();
        let mut seen = HashSet::with_capacity(triangles.len());
        let mut faces = Vec::with_capacity(triangles.len());
        let mut quadric = vec![Quadric::default(); n];
        let mut normals = Vec::with_capacity(triangles.len());
        for t in triangles {
            let f = t.map(|i| welded[i as usize]);
            let mut key = f;
            key.sort_unstable();
            if key[0] == key[1] || key[1] == key[2] || !seen.insert(key) {
                continue;
            }
            let normal = face_normal(f.map(|i| position[i as usize]));
            if normal.norm_squared() <= 0.0 {
                continue;
            }
            let area = 0.5 * normal.norm();
            let normal = normal.normalize();
            let plane = Quadric::plane(normal, position[f[0] as usize], area);
            for &v in &f {
                quadric[v as usize].add(&plane);
            }
            faces.push(f);
            normals.push((normal, area));
        }
        let mut edge_faces: HashMap<(u32, u32), u32> = HashMap::with_capacity(faces.len() * 2);
        let mut edges = Vec::with_capacity(faces.len() * 3 / 2);
        let edges_of = |f: &[u32; 3]| [(f[0], f[1]), (f[1], f[2]), (f[2], f[0])];
        for f in &faces {
            for (a, b) in edges_of(f) {
                let count = edge_faces.entry((a.min(b), a.max(b))).or_default();
                if *count == 0 {
                    edges.push((a, b));
                }
                *count += 1;
            }
        }
        let mut boundary = vec![false; n];
        let mut locked = vec![false; n];
        for (f, &(normal, area)) in faces.iter().zip(&normals) {
            for (a, b) in edges_of(f) {
                match edge_faces[&(a.min(b), a.max(b))] {
                    1 => {
                        let (pa, pb) = (position[a as usize], position[b as usize]);
                        let across = (pb - pa).cross(&normal);
                        if across.norm_squared() > 0.0 {
                            let rim = Quadric::plane(across.normalize(), pa, area);
                            quadric[a as usize].add(&rim);
                            quadric[b as usize].add(&rim);
                        }
                        boundary[a as usize] = true;
                        boundary[b as usize] = true;
                    }
                    2 => {}
                    _ => {
                        locked[a as usize] = true;
                        locked[b as usize] = true;
                    }
                }
            }
        }
        let mut vertex_faces = vec![Vec::new(); n];
        let mut face_points = vec![Vec::new(); faces.len()];
        let mut placed = vec![false; n];
        for (k, f) in faces.iter().enumerate() {
            for &v in f {
                vertex_faces[v as usize].push(k as u32);
                if !std::mem::replace(&mut placed[v as usize], true) {
                    face_points[k].push(v);
                }
            }
        }
        // The input's triangle centres are checked too: between sparse vertices a coarse chord could stray.
        let mut input = position.clone();
        for (k, f) in faces.iter().enumerate() {
            let centre = f
                .iter()
                .map(|&v| position[v as usize])
                .sum::<Vector3<f64>>()
                / 3.0;
            face_points[k].push(input.len() as u32);
            input.push(centre);
        }
        let mut collapser = Self {
            tolerance,
            input,
            face_points,
            moves: Vec::new(),
            position,
            quadric,
            boundary,
            locked,
            alive: vec![true; n],
            version: vec![0; n],
            face_alive: vec![true; faces.len()],
            faces,
            vertex_faces,
            queue: BinaryHeap::with_capacity(edge_faces.len()),
        };
        for (a, b) in edges {
            collapser.queue_edge(a, b);
        }
        collapser
    }

    /// Queues the cheapest placement of `a` and `b` merged: the quadric's minimiser when it is well defined and
    /// near the edge, else the better of the two ends and the midpoint.
    fn queue_edge(&mut self, a: u32, b: u32) {
        if self.locked[a as usize] || self.locked[b as usize] {
            return;
        }
        let mut q = self.quadric[a as usize];
        q.add(&self.quadric[b as usize]);
        let (pa, pb) = (self.position[a as usize], self.position[b as usize]);
        let mid = (pa + pb) * 0.5;
        let mut best = (q.mean_error(&mid), mid);
        for p in [pa, pb] {
            let e = q.mean_error(&p);
            if e < best.0 {
                best = (e, p);
            }
        }
        if let Some(m) = q
            .minimiser()
            .filter(|m| (m - mid).norm() <= (pb - pa).norm())
        {
            let e = q.mean_error(&m);
            if e < best.0 {
                best = (e, m);
            }
        }
        self.queue.push(Candidate {
            cost: best.0,
            a,
            b,
            version_a: self.version[a as usize],
            version_b: self.version[b as usize],
            target: best.1,
        });
    }

    /// Collapses the cheapest valid edges until none is left or the cheapest's mean squared distance to its planes
    /// already exceeds the tolerance (then its largest would too). Returns how many it made.
    fn run(&mut self) -> usize {
        let max_cost = self.tolerance * self.tolerance;
        let mut collapses = 0;
        while let Some(c) = self.queue.pop() {
            if c.cost > max_cost {
                break;
            }
            let (a, b) = (c.a as usize, c.b as usize);
            if !(self.alive[a] && self.alive[b])
                || self.version[a] != c.version_a
                || self.version[b] != c.version_b
                || !self.may_collapse(c.a, c.b, c.target)
            {
                continue;
            }
            self.collapse(c.a, c.b, c.target);
            collapses += 1;
        }
        collapses
    }

    /// The largest distance from a checked input point to the triangle it belongs to, metres: at least its
    /// distance to the whole result.
    fn largest_distance(&self) -> f64 {
        self.face_points
            .iter()
            .enumerate()
            .filter(|&(f, _)| self.face_alive[f])
            .flat_map(|(f, points)| {
                let t = self.faces[f].map(|v| self.position[v as usize]);
                points
                    .iter()
                    .map(move |&p| point_triangle_distance(self.input[p as usize], t))
            })
            .fold(0.0, f64::max)
    }

    fn neighbours(&self, v: u32) -> Vec<u32> {
        let mut out: Vec<u32> = self.vertex_faces[v as usize]
            .iter()
            .flat_map(|&f| self.faces[f as usize])
            .filter(|&u| u != v)
            .collect();
        out.sort_unstable();
        out.dedup();
        out
    }

    /// Whether merging `b` into `a` at `target` keeps the surface a surface: the edge still exists between one or two
    /// triangles, the two ends share no neighbour but the edge's opposite corners (the link condition), an inner edge
    /// does not join two rims, triangles stay around the merged vertex (three inside the surface, one on a rim: a
    /// closed tetrahedron of a manifold surface does not fold into two coincident triangles), no more than
    /// [`MAX_FAN`] are involved, and no surviving triangle
    /// flips, turns too far or degenerates.
    /// Also checks that the input vertices of the changed triangles stay within the tolerance of the merged
    /// vertex's triangles, and notes where each goes in `moves`.
    fn may_collapse(&mut self, a: u32, b: u32, target: Vector3<f64>) -> bool {
        let around_a = &self.vertex_faces[a as usize];
        let around_b = &self.vertex_faces[b as usize];
        // Checked first, in constant time: a hub (a fanned cap's centre, a sphere's pole) is met again after each
        // collapse beside it, and checking its whole fan each time grew with the cube of its valence.
        if around_a.len() + around_b.len() > MAX_FAN {
            return false;
        }
        let shared: Vec<u32> = around_a
            .iter()
            .copied()
            .filter(|&f| self.faces[f as usize].contains(&b))
            .collect();
        if shared.is_empty() || shared.len() > 2 {
            return false;
        }
        if shared.len() == 2 && self.boundary[a as usize] && self.boundary[b as usize] {
            return false;
        }
        let merged = around_a.len() + around_b.len() - 2 * shared.len();
        let on_rim = self.boundary[a as usize] || self.boundary[b as usize];
        if merged < if on_rim { 1 } else { 3 } {
            return false;
        }
        let neighbours_b = self.neighbours(b);
        let common = self
            .neighbours(a)
            .into_iter()
            .filter(|u| neighbours_b.binary_search(u).is_ok())
            .count();
        if common != shared.len() {
            return false;
        }
        let mut fan = Vec::with_capacity(merged);
        for &f in around_a.iter().chain(around_b) {
            let face = self.faces[f as usize];
            if face.contains(&a) && face.contains(&b) {
                continue;
            }
            let before = face.map(|v| self.position[v as usize]);
            let after = face.map(|v| {
                if v == a || v == b {
                    target
                } else {
                    self.position[v as usize]
                }
            });
            let (n0, n1) = (face_normal(before), face_normal(after));
            let (l0, l1) = (n0.norm(), n1.norm());
            if l1 <= 1e-6 * l0 || n0.dot(&n1) < MIN_NORMAL_COS * l0 * l1 {
                return false;
            }
            fan.push((f, after));
        }
        let mut moves = std::mem::take(&mut self.moves);
        moves.clear();
        // Shared triangles are around both ends: count them with `a`'s.
        let changed = around_a.iter().chain(
            around_b
                .iter()
                .filter(|&&f| !self.faces[f as usize].contains(&a)),
        );
        for &f in changed {
            for &p in &self.face_points[f as usize] {
                let point = self.input[p as usize];
                let (d, nearest) = fan
                    .iter()
                    .map(|&(g, t)| (point_triangle_distance(point, t), g))
                    .fold((f64::INFINITY, u32::MAX), |best, c| {
                        if c.0 < best.0 { c } else { best }
                    });
                if d.is_nan() || d > self.tolerance {
                    self.moves = moves;
                    return false;
                }
                moves.push((p, nearest));
            }
        }
        self.moves = moves;
        true
    }

    /// Merges `b` into `a` at `target`; the input vertices go where [`Self::may_collapse`] noted.
    fn collapse(&mut self, a: u32, b: u32, target: Vector3<f64>) {
        for &f in self.vertex_faces[a as usize]
            .iter()
            .chain(&self.vertex_faces[b as usize])
        {
            self.face_points[f as usize].clear();
        }
        for &(p, f) in &self.moves {
            self.face_points[f as usize].push(p);
        }
        let around_b = std::mem::take(&mut self.vertex_faces[b as usize]);
        for f in around_b {
            let face = self.faces[f as usize];
            if face.contains(&a) {
                self.face_alive[f as usize] = false;
                for v in face {
                    if v != b {
                        self.vertex_faces[v as usize].retain(|&g| g != f);
                    }
                }
            } else {
                for v in &mut self.faces[f as usize] {
                    if *v == b {
                        *v = a;
                    }
                }
                self.vertex_faces[a as usize].push(f);
            }
        }
        let (ai, bi) = (a as usize, b as usize);
        self.position[ai] = target;
        let qb = self.quadric[bi];
        self.quadric[ai].add(&qb);
        self.boundary[ai] |= self.boundary[bi];
        self.alive[bi] = false;
        self.version[ai] += 1;
        self.version[bi] += 1;
        for n in self.neighbours(a) {
            self.queue_edge(a, n);
        }
    }

    /// The surviving vertices (metres, numbered in order of first use) and triangles.
    fn into_parts(self) -> (Vec<Point3<f32>>, Vec<[u32; 3]>) {
        let mut index = vec![u32::MAX; self.position.len()];
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        for (face, _) in self
            .faces
            .iter()
            .zip(&self.face_alive)
            .filter(|(_, alive)| **alive)
        {
            triangles.push(face.map(|v| {
                let slot = &mut index[v as usize];
                if *slot == u32::MAX {
                    *slot = positions.len() as u32;
                    positions.push(Point3::from(self.position[v as usize].cast::<f32>()));
                }
                *slot
            }));
        }
        (positions, triangles)
    }
}

#[cfg(test)]
mod tests;

//! Smooth vertex normals for a simplified mesh whose input had them: a smooth surface simplified to a few wide
//! facets is still smooth, and its facets' own normals would be off by half the angle between neighbours (15
//! degrees on a thin cylinder cut to a dozen sides).

use super::MeshParts;
use nalgebra::{Point3, Vector3};
use std::collections::HashMap;

/// Per-corner normals, averaged (by area) over the triangles around each vertex that turn by at most the crease
/// angle (its cosine `crease_cos`) from the corner's own triangle; a vertex gets one copy per distinct normal.
/// Returns the positions, unit normals and triangles of the result.
pub(super) fn crease_normals(
    positions: &[Point3<f32>],
    triangles: &[[u32; 3]],
    crease_cos: f64,
) -> MeshParts {
    let p = |i: u32| positions[i as usize].cast::<f64>().coords;
    // Area-weighted (twice the area) face normals.
    let face: Vec<Vector3<f64>> = triangles
        .iter()
        .map(|t| (p(t[1]) - p(t[0])).cross(&(p(t[2]) - p(t[0]))))
        .collect();
    let unit: Vec<Vector3<f64>> = face
        .iter()
        .map(|n| n.try_normalize(0.0).unwrap_or_else(Vector3::zeros))
        .collect();
    let mut around = vec![Vec::new(); positions.len()];
    for (f, t) in triangles.iter().enumerate() {
        for &v in t {
            around[v as usize].push(f);
        }
    }
    let mut out_positions = Vec::with_capacity(positions.len());
    let mut out_normals = Vec::with_capacity(positions.len());
    let mut index: HashMap<(u32, [u32; 3]), u32> = HashMap::with_capacity(positions.len());
    let out_triangles = triangles
        .iter()
        .enumerate()
        .map(|(f, t)| {
            t.map(|v| {
                let sum: Vector3<f64> = around[v as usize]
                    .iter()
                    .filter(|&&g| unit[g].dot(&unit[f]) >= crease_cos)
                    .map(|&g| face[g])
                    .sum();
                // A triangle that rounded to nothing in f32 has no normal of its own: any unit vector keeps the
                // mesh's normals valid, and it renders nothing.
                let n = sum
                    .try_normalize(0.0)
                    .or_else(|| unit[f].try_normalize(0.0))
                    .unwrap_or_else(Vector3::z)
                    .cast::<f32>();
                let key = (v, [n.x.to_bits(), n.y.to_bits(), n.z.to_bits()]);
                *index.entry(key).or_insert_with(|| {
                    out_positions.push(positions[v as usize]);
                    out_normals.push(n);
                    (out_positions.len() - 1) as u32
                })
            })
        })
        .collect();
    MeshParts {
        positions: out_positions,
        normals: out_normals,
        triangles: out_triangles,
        ..MeshParts::default()
    }
}

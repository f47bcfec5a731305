//! Closure, size, determinism, symmetry, texture and naming checks over every family.

use super::super::model::ObjectModel;
use super::super::solid::checks;
use super::super::texture::TEXTURE_SIZE;
use super::{NovelFamily, NovelObject, generate, novel_name, parse_spec};
use crate::objects::{render_preview, write_object};
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use scene::mesh::{MeshLoadOptions, Symmetry, load_obj};
use std::collections::HashMap;
use std::f64::consts::TAU;

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
    let families: std::collections::HashSet<_> = (7000..7006).map(NovelFamily::for_seed).collect();
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

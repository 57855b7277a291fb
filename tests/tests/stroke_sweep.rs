//! A stroke is one connected piece at any mouse speed: two far-apart points are joined by the
//! brush's shape swept between them. For every shape and mode, with and without mirror
//! symmetry, the voxels a two-point stroke changes are exactly the swept voxels of a
//! voxel-by-voxel reference written here from the definitions (capsules for the sphere, the
//! shape stamped at steps of at most one voxel per axis for the voxel, cube and cylinder), and
//! each mirror image of them is one 26-connected component.

use app::editor::Document;
use app::editor::command::{Axis, BrushMode, BrushShape, Command, Mirror, Stroke};
use app::editor::history::History;
use app::scene::Scene;
use brickmap::{GridDims, Shape};
use glam::{DVec3, IVec3, UVec3};
use std::collections::BTreeSet;

const SIZE: UVec3 = UVec3::new(104, 32, 48);
const MATERIAL: u8 = 2;

/// An empty document (attach), or one solid with material 1 (erase and paint change its
/// voxels).
fn document(mode: BrushMode) -> Document {
    let scene = Scene::empty(GridDims::from_voxels(SIZE).unwrap(), 2).unwrap();
    for colour in [10, 20] {
        scene
            .world
            .push_material(brickmap::Material {
                kind: brickmap::MaterialKind::Lambertian,
                param: 0,
                colour,
            })
            .unwrap();
    }
    if mode != BrushMode::Attach {
        scene
            .edit(brickmap::EditOp::Shape {
                shape: Shape::Box {
                    min: IVec3::ZERO,
                    max: SIZE.as_ivec3() - 1,
                },
                mode: brickmap::Mode::Add(1),
            })
            .unwrap();
    }
    Document::new(scene, History::default())
}

/// Every voxel and its material.
fn voxels(doc: &Document) -> Vec<(IVec3, Option<u8>)> {
    let view = doc.scene.world.read();
    let mut out = Vec::new();
    for x in 0..SIZE.x as i32 {
        for y in 0..SIZE.y as i32 {
            for z in 0..SIZE.z as i32 {
                let v = IVec3::new(x, y, z);
                out.push((v, view.voxel(v).unwrap()));
            }
        }
    }
    out
}

fn centre(v: IVec3) -> DVec3 {
    v.as_dvec3() + 0.5
}

fn dist2_to_segment(c: DVec3, a: DVec3, b: DVec3) -> f64 {
    let ab = b - a;
    let t = if ab.length_squared() == 0.0 {
        0.0
    } else {
        ((c - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
    };
    (c - (a + ab * t)).length_squared()
}

/// The reference: whether voxel `v` is swept by a stroke of `shape` from `a` to `b`.
fn swept(shape: BrushShape, size: f64, axis: DVec3, a: DVec3, b: DVec3, v: IVec3) -> bool {
    let c = centre(v);
    // Stamps: n = ⌈largest axis distance⌉ equal steps.
    let n = (b - a).abs().max_element().ceil().max(1.0) as i32;
    let stamp = |k: i32| {
        if k == n {
            b
        } else {
            a + (b - a) * (k as f64 / n as f64)
        }
    };
    match shape {
        BrushShape::Sphere | BrushShape::Line => dist2_to_segment(c, a, b) <= size * size,
        BrushShape::Voxel => (0..=n).any(|k| stamp(k).floor().as_ivec3() == v),
        BrushShape::Cube => {
            let h = size.round() as i32;
            (0..=n).any(|k| {
                let d = (v - stamp(k).floor().as_ivec3()).abs();
                d.max_element() <= h
            })
        }
        BrushShape::Cylinder => (0..=n).any(|k| {
            let p = stamp(k);
            let (ca, cb) = (p - axis * size, p + axis * size);
            let ab = cb - ca;
            let s = (c - ca).dot(ab) / ab.length_squared();
            (0.0..=1.0).contains(&s) && (c - (ca + ab * s)).length_squared() <= size * size
        }),
        BrushShape::Box => {
            let (lo, hi) = (
                a.floor().as_ivec3().min(b.floor().as_ivec3()),
                a.floor().as_ivec3().max(b.floor().as_ivec3()),
            );
            v.cmpge(lo).all() && v.cmple(hi).all()
        }
    }
}

/// The 26-connected pieces of a voxel set.
fn components(set: &BTreeSet<(i32, i32, i32)>) -> usize {
    let mut v = brickmap::VoxelSet::new();
    for &(x, y, z) in set {
        v.insert(IVec3::new(x, y, z));
    }
    v.components()
}

fn reflect(p: DVec3, m: &Mirror, combo: usize) -> DVec3 {
    let mut q = p;
    let axes: Vec<usize> = [(0, m.x), (1, m.y), (2, m.z)]
        .into_iter()
        .filter(|a| a.1)
        .map(|a| a.0)
        .collect();
    for (k, &axis) in axes.iter().enumerate() {
        if combo >> k & 1 == 1 {
            q[axis] = 2.0 * m.centre[axis] - q[axis];
        }
    }
    q
}

#[test]
fn two_far_points_give_exactly_the_swept_voxels_as_one_connected_piece() {
    use BrushShape::*;
    // 39 voxels apart along x, 14 along y, 30 along z: a drag much faster than one voxel per
    // event; off-centre coordinates so stamps fall between voxel centres.
    let (a, b) = (DVec3::new(6.3, 8.6, 8.2), DVec3::new(44.9, 22.1, 37.7));
    for shape in [Voxel, Sphere, Cube, Cylinder, Line, Box] {
        for mode in [BrushMode::Attach, BrushMode::Erase, BrushMode::Paint] {
            for mirror in [false, true] {
                let what = format!("{shape:?} {mode:?} mirror {mirror}");
                let m = Mirror {
                    x: mirror,
                    centre: DVec3::new(52.0, 0.0, 0.0),
                    ..Mirror::default()
                };
                let stroke = Stroke {
                    mode,
                    shape,
                    size: 2.0,
                    material: MATERIAL,
                    mirror: m.clone(),
                    points: vec![a, b],
                    axis: Axis::Z,
                    in_selection: false,
                    paint: Default::default(),
                };
                let mut doc = document(mode);
                let before = voxels(&doc);
                doc.execute(Command::Stroke(stroke)).unwrap();
                let after = voxels(&doc);
                let changed: BTreeSet<(i32, i32, i32)> = before
                    .iter()
                    .zip(&after)
                    .filter(|(x, y)| x.1 != y.1)
                    .map(|(x, _)| (x.0.x, x.0.y, x.0.z))
                    .collect();
                let images = if mirror { 2 } else { 1 };
                let mut expected = BTreeSet::new();
                for combo in 0..images {
                    let (ra, rb) = (reflect(a, &m, combo), reflect(b, &m, combo));
                    let mut image = BTreeSet::new();
                    for (v, _) in &before {
                        if swept(shape, 2.0, DVec3::Z, ra, rb, *v) {
                            image.insert((v.x, v.y, v.z));
                        }
                    }
                    assert!(image.len() >= 38, "{what}: {} voxels", image.len());
                    assert_eq!(
                        components(&image),
                        1,
                        "{what}: image {combo} is not one piece"
                    );
                    expected.extend(image);
                }
                assert_eq!(changed.len(), expected.len(), "{what}: voxel count");
                assert!(changed == expected, "{what}: not exactly the swept voxels");
                // What they became.
                for (x, y) in before.iter().zip(&after) {
                    if x.1 != y.1 {
                        let want = match mode {
                            BrushMode::Erase => None,
                            _ => Some(MATERIAL),
                        };
                        assert_eq!(y.1, want, "{what} at {}", x.0);
                    }
                }
            }
        }
    }
}

#[test]
fn a_live_stroke_of_far_apart_segments_is_connected_and_replays_to_its_hash() {
    use BrushShape::*;
    let points = [
        DVec3::new(5.5, 20.5, 5.5),
        DVec3::new(60.5, 20.5, 9.5),
        DVec3::new(62.5, 28.5, 40.5),
        DVec3::new(10.5, 4.5, 44.5),
    ];
    for shape in [Voxel, Sphere, Cube, Cylinder] {
        let stroke = Stroke {
            mode: BrushMode::Attach,
            shape,
            size: 1.0,
            material: MATERIAL,
            mirror: Mirror::default(),
            points: points[..1].to_vec(),
            axis: Axis::Y,
            in_selection: false,
            paint: Default::default(),
        };
        let mut live = document(BrushMode::Attach);
        live.begin_stroke(stroke.clone()).unwrap();
        for p in &points[1..] {
            live.extend_stroke(&[*p]).unwrap();
        }
        live.end_stroke().unwrap().expect("a stroke was open");
        let solid: BTreeSet<(i32, i32, i32)> = voxels(&live)
            .into_iter()
            .filter(|(_, m)| m.is_some())
            .map(|(v, _)| (v.x, v.y, v.z))
            .collect();
        assert_eq!(components(&solid), 1, "{shape:?}: the stroke is in pieces");
        for p in points {
            let v = p.floor().as_ivec3();
            assert!(
                solid.contains(&(v.x, v.y, v.z)),
                "{shape:?}: {v} not reached"
            );
        }
        let mut at_once = document(BrushMode::Attach);
        at_once
            .execute(Command::Stroke(Stroke {
                points: points.to_vec(),
                ..stroke
            }))
            .unwrap();
        assert_eq!(
            live.scene.world.read().content_hash(),
            at_once.scene.world.read().content_hash(),
            "{shape:?}: live and replayed strokes differ"
        );
    }
}

//! The light faces: exact under edits across brick and slab boundaries, under material
//! changes, and sampled in proportion to their weights.

use brickmap::{
    EditOp, GpuBuffer, GridDims, Material, MaterialKind, Mode, Shape, VoxelEdit, VoxelOp, World,
    WorldConfig,
};
use glam::IVec3;

/// 128 × 16 × 32 voxels in 4 slabs (slab boundaries at x = 32, 64, 96).
fn world() -> (World, u8) {
    let w = World::new(
        GridDims::new(16, 2, 4).unwrap(),
        WorldConfig::with_workers(4),
    )
    .unwrap();
    assert_eq!(w.workers(), 4);
    let lamp = w
        .push_material(Material {
            kind: MaterialKind::Emissive,
            param: 0,
            colour: 0, // white
        })
        .unwrap();
    // A floor at y = 0.
    w.apply(EditOp::Shape {
        shape: Shape::Box {
            min: IVec3::ZERO,
            max: IVec3::new(127, 0, 31),
        },
        mode: Mode::Add(0),
    })
    .unwrap();
    (w, lamp)
}

fn set(w: &World, v: IVec3, op: VoxelOp) {
    w.apply(EditOp::Voxels(vec![VoxelEdit { pos: v, op }]))
        .unwrap();
}

fn faces(w: &World) -> Vec<(IVec3, u8)> {
    let v = w.read();
    v.validate().unwrap();
    let mut f: Vec<(IVec3, u8)> = v.lights().iter().map(|(_, f)| (f.voxel, f.face)).collect();
    f.sort_by_key(|(v, k)| (v.to_array(), *k));
    f
}

#[test]
fn a_lamp_has_its_uncovered_faces_across_bricks_and_slabs() {
    let (w, lamp) = world();
    assert!(w.read().lights().is_empty());
    // On the floor, against the slab boundary at x = 32 (its +x neighbour is another slab's).
    let at = IVec3::new(31, 1, 9);
    set(&w, at, VoxelOp::Set(lamp));
    let f = faces(&w);
    assert_eq!(f.len(), 5, "{f:?}"); // not the face on the floor
    assert!(f.iter().all(|(v, k)| *v == at && *k != 2));
    let weight = w.read().lights().weight(lamp);
    assert!(weight > 2.9 && weight < 3.1, "white × strength 1: {weight}");
    assert_eq!(w.read().lights().total(), 5.0 * weight);
    // A voxel in the next slab covers the +x face.
    let blocker = IVec3::new(32, 1, 9);
    set(&w, blocker, VoxelOp::Set(0));
    assert_eq!(faces(&w).len(), 4);
    assert!(!faces(&w).iter().any(|(_, k)| *k == 1));
    // Erasing it (an edit of the other slab only) uncovers it again.
    set(&w, blocker, VoxelOp::Clear);
    assert_eq!(faces(&w).len(), 5);
    // Erasing the floor under the lamp (another brick) uncovers the bottom face.
    set(&w, at - IVec3::Y, VoxelOp::Clear);
    assert_eq!(faces(&w).len(), 6);
    // A buried lamp has none; uncovering one of its faces from a neighbouring brick adds it.
    let cube = Shape::Box {
        min: IVec3::new(60, 1, 4),
        max: IVec3::new(70, 10, 14),
    };
    w.apply(EditOp::Shape {
        shape: cube,
        mode: Mode::Add(0),
    })
    .unwrap();
    let buried = IVec3::new(63, 5, 8); // last voxel of its brick in x, slab boundary at 64
    set(&w, buried, VoxelOp::Set(lamp));
    assert_eq!(faces(&w).len(), 6);
    set(&w, buried + IVec3::X, VoxelOp::Clear);
    assert_eq!(faces(&w).len(), 7);
    // Erasing every lamp leaves nothing to sample, and no NaN anywhere.
    w.apply(EditOp::Shape {
        shape: Shape::Box {
            min: IVec3::ZERO,
            max: IVec3::new(127, 15, 31),
        },
        mode: Mode::Remove,
    })
    .unwrap();
    let v = w.read();
    v.validate().unwrap();
    assert!(v.lights().is_empty());
    assert_eq!(v.lights().total(), 0.0);
    assert_eq!(v.lights().sample(0.5), None);
}

#[test]
fn material_changes_reweigh_without_touching_voxels() {
    let (w, lamp) = world();
    w.apply(EditOp::Shape {
        shape: Shape::Box {
            min: IVec3::new(10, 1, 10),
            max: IVec3::new(12, 3, 12),
        },
        mode: Mode::Add(lamp),
    })
    .unwrap();
    let before = faces(&w);
    assert_eq!(before.len(), 9 * 5); // a 3³ cube on the floor
    let _ = w.take_dirty();
    // A stronger lamp: the weights change, the faces do not, no voxel byte is dirty.
    w.set_param(MaterialKind::Emissive, 0, 4.0).unwrap();
    assert_eq!(faces(&w), before);
    let total = w.read().lights().total();
    let weight = w.read().lights().weight(lamp);
    assert!(weight > 11.9 && weight < 12.1, "{weight}");
    assert!((total - 45.0 * weight).abs() <= 1e-4 * total);
    let dirty = w.take_dirty();
    assert!(
        dirty.of(GpuBuffer::Bricks).is_empty() && dirty.of(GpuBuffer::MaterialBytes).is_empty()
    );
    assert!(!dirty.of(GpuBuffer::Lights).is_empty());
    // Black emits nothing: no light faces; a colour back brings them back.
    let old = w.set_colour(0, [0, 0, 0]);
    assert!(faces(&w).is_empty());
    w.set_colour(0, old);
    assert_eq!(faces(&w), before);
    // The material stops being emissive, and becomes emissive again (a rescan).
    let m = w.read().materials().get(lamp).unwrap();
    w.set_material(
        lamp,
        Material {
            kind: MaterialKind::Lambertian,
            ..m
        },
    )
    .unwrap();
    assert!(faces(&w).is_empty());
    w.set_material(lamp, m).unwrap();
    assert_eq!(faces(&w), before);
}

#[test]
fn an_edit_away_from_the_lamps_writes_no_light_byte() {
    let (w, lamp) = world();
    set(&w, IVec3::new(5, 1, 5), VoxelOp::Set(lamp));
    let _ = w.take_dirty();
    w.apply(EditOp::Shape {
        shape: Shape::Sphere {
            centre: glam::DVec3::new(90.0, 6.0, 20.0),
            radius: 8.0,
        },
        mode: Mode::Add(0),
    })
    .unwrap();
    let dirty = w.take_dirty();
    assert!(!dirty.of(GpuBuffer::Bricks).is_empty());
    assert!(dirty.of(GpuBuffer::Lights).is_empty());
}

#[test]
fn faces_are_sampled_in_proportion_to_their_weights() {
    let (w, lamp) = world();
    let bright = w
        .push_material(Material {
            kind: MaterialKind::Emissive,
            param: 1,
            colour: 40,
        })
        .unwrap();
    w.set_param(MaterialKind::Emissive, 1, 50.0).unwrap();
    for (i, x) in [3, 20, 40, 77, 100].into_iter().enumerate() {
        let m = if i % 2 == 0 { lamp } else { bright };
        set(&w, IVec3::new(x, 1 + i as i32, 7), VoxelOp::Set(m));
    }
    let v = w.read();
    v.validate().unwrap();
    let lights = v.lights();
    let n = 400_000u32;
    let mut counts = std::collections::HashMap::new();
    let mut rng = 0x1234_5678_9abc_def0u64;
    for _ in 0..n {
        rng = rng
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let u = (rng >> 11) as f64 / (1u64 << 53) as f64;
        *counts.entry(lights.sample(u).unwrap()).or_insert(0u32) += 1;
    }
    let total = lights.total() as f64;
    let mut slots = 0;
    for (slot, _) in lights.iter() {
        slots += 1;
        let p = lights.leaf(slot) as f64 / total;
        let expected = p * n as f64;
        let got = *counts.get(&slot).unwrap_or(&0) as f64;
        let sigma = (n as f64 * p * (1.0 - p)).sqrt();
        assert!(
            (got - expected).abs() < 5.0 * sigma + 1.0,
            "slot {slot}: {got} vs {expected}"
        );
    }
    assert_eq!(slots, lights.len());
    // Only light slots are ever drawn.
    assert_eq!(counts.len() as u32, lights.len());
}

#[test]
fn a_point_draws_faces_by_importance_with_the_probability_it_reports() {
    let (w, lamp) = world();
    // 60 lamps in a pseudo-random scatter, then a third of them erased and 20 more added (free
    // slots reused, the capacity grown, the table's entries moved by removals).
    let mut rng = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = |n: u32| {
        rng = rng
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((rng >> 33) % n as u64) as i32
    };
    let mut at = Vec::new();
    for _ in 0..80 {
        at.push(IVec3::new(next(128), 1 + next(14), next(32)));
    }
    for v in &at[..60] {
        set(&w, *v, VoxelOp::Set(lamp));
    }
    for v in at[..60].iter().step_by(3) {
        set(&w, *v, VoxelOp::Clear);
    }
    for v in &at[60..] {
        set(&w, *v, VoxelOp::Set(lamp));
    }
    let v = w.read();
    v.validate().unwrap();
    let lights = v.lights();
    for (slot, f) in lights.iter() {
        assert_eq!(lights.slot_of(f.voxel, f.face), Some(slot));
    }
    assert_eq!(lights.slot_of(IVec3::new(0, 0, 0), 0), None);
    let points = [
        (glam::DVec3::new(20.5, 1.0, 9.5), IVec3::Y), // on the floor
        (glam::DVec3::new(64.0, 8.25, 16.5), IVec3::NEG_X),
        (glam::DVec3::new(100.5, 15.0, 0.5), IVec3::Z),
    ];
    // The binary descent and the 4- and 8-wide steps over the same tree.
    for ((p, n), levels) in points
        .into_iter()
        .flat_map(|q| (1..=3).map(move |l| (q, l)))
    {
        let mut sum = 0.0;
        for (slot, f) in lights.iter() {
            let prob = lights.probability_stepping(slot, p, n, levels);
            sum += prob;
            // A face whose centre is in front of it and of the receiver has a chance.
            let centre = f.voxel.as_dvec3() + 0.5 + f.normal().as_dvec3() * 0.5;
            let seen = (p - centre).dot(f.normal().as_dvec3()) > 0.0
                && (centre - p).dot(n.as_dvec3()) > 0.0;
            assert!(
                !seen || prob > 0.0,
                "{p} {n} {levels}: face {f:?} has no chance"
            );
        }
        assert!(sum > 0.5 && sum <= 1.0 + 1e-9, "{p} {n} {levels}: {sum}");
        let draws = 200_000u32;
        let mut counts = std::collections::HashMap::new();
        for k in 0..draws {
            let u = (k as f64 + 0.5) / draws as f64;
            if let Some((slot, prob)) = lights.sample_stepping(u, p, n, levels) {
                let expected = lights.probability_stepping(slot, p, n, levels);
                assert!(
                    (prob - expected).abs() <= 1e-12 * expected,
                    "{prob} {expected}"
                );
                *counts.entry(slot).or_insert(0u32) += 1;
            }
        }
        for (slot, _) in lights.iter() {
            let expected = lights.probability_stepping(slot, p, n, levels) * draws as f64;
            let got = *counts.get(&slot).unwrap_or(&0) as f64;
            // Stratified u: the counts are exact up to the rounding of each subtree's share.
            assert!(
                (got - expected).abs() < 2.0 + 1e-3 * expected,
                "slot {slot}: {got} vs {expected}"
            );
        }
    }
}

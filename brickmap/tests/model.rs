//! Model-based test: random sequences of every edit against a dense reference grid, run on
//! worlds with 1, 2 and 4 workers. After every step: every voxel and material (popcount-order
//! lookups), the slab invariants (bucket accounting, coarse exactness, slots), every changed
//! GPU byte covered by a drained dirty range, the inverse restoring the prior content hash and
//! its own inverse re-applying the edit, and the same hash whatever the worker count.

use brickmap::{
    EditOp, GpuBuffer, GridDims, Material, MaterialKind, Mode, Shape, VoxelEdit, VoxelOp, World,
    WorldConfig,
};
use glam::{DVec3, IVec3};
use proptest::prelude::*;

const DIMS: (u32, u32, u32) = (9, 3, 5); // 72 × 24 × 40 voxels: 3 coarse columns
const MATERIALS: u8 = 6;

#[derive(Clone, Debug)]
enum Step {
    Edit(EditOp),
    /// Undo the edit `k` steps back (clamped) if it is the latest; exercised via restore.
    UndoLast,
}

fn coord(max: i32) -> impl Strategy<Value = f64> {
    (-8i32 * 4..(max + 8) * 4).prop_map(|q| q as f64 / 4.0)
}

fn point() -> impl Strategy<Value = DVec3> {
    (coord(72), coord(24), coord(40)).prop_map(|(x, y, z)| DVec3::new(x, y, z))
}

fn material() -> impl Strategy<Value = u8> {
    prop_oneof![9 => 0..MATERIALS, 1 => MATERIALS..=255u8]
}

fn mode() -> impl Strategy<Value = Mode> {
    prop_oneof![
        3 => material().prop_map(Mode::Add),
        2 => Just(Mode::Remove),
        2 => material().prop_map(Mode::Paint),
    ]
}

fn shape() -> impl Strategy<Value = Shape> {
    let ivec = (-4..76i32, -4..28i32, -4..44i32).prop_map(|(x, y, z)| IVec3::new(x, y, z));
    prop_oneof![
        ivec.clone().prop_map(Shape::Voxel),
        (point(), 0.25f64..20.0).prop_map(|(centre, radius)| Shape::Sphere { centre, radius }),
        (ivec.clone(), ivec).prop_map(|(a, b)| Shape::Box {
            min: a.min(b),
            max: a.max(b)
        }),
        (point(), point(), 0.5f64..9.0).prop_map(|(a, b, radius)| {
            let b = if a == b { b + DVec3::X } else { b };
            Shape::Cylinder { a, b, radius }
        }),
        (prop::collection::vec(point(), 1..4), 0.5f64..6.0)
            .prop_map(|(points, radius)| Shape::Line { points, radius }),
    ]
}

fn voxels() -> impl Strategy<Value = Vec<VoxelEdit>> {
    let op = prop_oneof![
        3 => (0..MATERIALS).prop_map(VoxelOp::Set),
        2 => Just(VoxelOp::Clear),
        1 => (0..MATERIALS).prop_map(VoxelOp::Paint),
    ];
    // Clustered positions, so bricks fill up and buckets grow and shrink.
    let pos = (0..72i32, 0..24i32, 0..40i32).prop_map(|(x, y, z)| IVec3::new(x, y, z));
    (
        pos,
        prop::collection::vec(((0..10i32, 0..10i32, 0..10i32), op), 1..300),
    )
        .prop_map(|(base, list)| {
            list.into_iter()
                .map(|((x, y, z), op)| VoxelEdit {
                    pos: (base + IVec3::new(x, y, z)).min(IVec3::new(71, 23, 39)),
                    op,
                })
                .collect()
        })
}

fn step() -> impl Strategy<Value = Step> {
    prop_oneof![
        6 => (shape(), mode()).prop_map(|(shape, mode)| Step::Edit(EditOp::Shape { shape, mode })),
        3 => voxels().prop_map(|v| Step::Edit(EditOp::Voxels(v))),
        1 => Just(Step::UndoLast),
    ]
}

struct Reference {
    voxels: Vec<Option<u8>>,
}

impl Reference {
    fn idx(v: IVec3) -> usize {
        (v.x + 72 * (v.y + 24 * v.z)) as usize
    }
    fn apply(&mut self, op: &EditOp) {
        match op {
            EditOp::Shape { shape, mode } => {
                for z in 0..40 {
                    for y in 0..24 {
                        for x in 0..72 {
                            let v = IVec3::new(x, y, z);
                            if !shape.contains(v) {
                                continue;
                            }
                            let slot = &mut self.voxels[Self::idx(v)];
                            match mode {
                                Mode::Add(m) => *slot = Some(*m),
                                Mode::Remove => *slot = None,
                                Mode::Paint(m) => {
                                    if slot.is_some() {
                                        *slot = Some(*m)
                                    }
                                }
                            }
                        }
                    }
                }
            }
            EditOp::Voxels(list) => {
                for e in list {
                    let slot = &mut self.voxels[Self::idx(e.pos)];
                    match e.op {
                        VoxelOp::Set(m) => *slot = Some(m),
                        VoxelOp::Clear => *slot = None,
                        VoxelOp::Paint(m) => {
                            if slot.is_some() {
                                *slot = Some(m)
                            }
                        }
                    }
                }
            }
            EditOp::Restore(_) | EditOp::Generate(_) => {
                unreachable!("the model never generates; undo uses snapshots")
            }
        }
    }
}

fn new_world(workers: usize) -> World {
    let (x, y, z) = DIMS;
    let w = World::new(
        GridDims::new(x, y, z).unwrap(),
        WorldConfig {
            workers,
            ..Default::default()
        },
    )
    .unwrap();
    for i in 1..MATERIALS {
        // Material 3 is emissive: every step also checks the light faces (validate) and
        // their dirty ranges.
        let kind = [
            MaterialKind::Lambertian,
            MaterialKind::Metal,
            MaterialKind::Dielectric,
            MaterialKind::Emissive,
        ][i as usize % 4];
        w.push_material(Material {
            kind,
            param: i,
            colour: 10 * i,
        })
        .unwrap();
    }
    w
}

fn images(w: &World) -> Vec<Vec<u8>> {
    let v = w.read();
    GpuBuffer::ALL.iter().map(|b| v.gpu_image(*b)).collect()
}

/// Every byte that differs between `before` and `after` lies in a drained range.
fn check_dirty(w: &World, before: &[Vec<u8>]) -> Result<(), TestCaseError> {
    let after = images(w);
    let dirty = w.take_dirty();
    for (i, b) in GpuBuffer::ALL.iter().enumerate() {
        let ranges = dirty.of(*b);
        for (k, byte) in after[i].iter().enumerate() {
            let old = before[i].get(k).copied().unwrap_or(0);
            if *byte != old {
                prop_assert!(
                    ranges.iter().any(|r| r.contains(&(k as u64))),
                    "{b:?} byte {k} changed outside the dirty ranges"
                );
            }
        }
    }
    Ok(())
}

fn check_contents(w: &World, r: &Reference) -> Result<(), TestCaseError> {
    let v = w.read();
    v.validate().map_err(TestCaseError::fail)?;
    let mut solid = 0;
    for z in 0..40 {
        for y in 0..24 {
            for x in 0..72 {
                let p = IVec3::new(x, y, z);
                let want = r.voxels[Reference::idx(p)];
                prop_assert_eq!(v.voxel(p).unwrap(), want, "voxel {}", p);
                solid += want.is_some() as u64;
            }
        }
    }
    prop_assert_eq!(v.solid_count(), solid);
    Ok(())
}

fn run_sequence(steps: &[Step]) -> Result<(), TestCaseError> {
    let worlds = [new_world(1), new_world(2), new_world(4)];
    prop_assert_eq!(
        worlds[2].workers(),
        3,
        "4 workers capped at 3 coarse columns"
    );
    let mut reference = Reference {
        voxels: vec![None; 72 * 24 * 40],
    };
    let mut history: Vec<(Vec<Option<u8>>, Vec<brickmap::EditInverse>)> = Vec::new();
    for w in &worlds {
        w.take_dirty();
    }
    for step in steps {
        match step {
            Step::Edit(op) => {
                let hashes_before: Vec<u64> =
                    worlds.iter().map(|w| w.read().content_hash()).collect();
                let snapshot = reference.voxels.clone();
                let mut inverses = Vec::new();
                let invalid = matches!(op, EditOp::Shape { mode: Mode::Add(m) | Mode::Paint(m), .. } if *m >= MATERIALS)
                    || matches!(op, EditOp::Shape { shape: Shape::Voxel(v), .. } if !GridDims::new(9, 3, 5).unwrap().contains_voxel(*v));
                for (w, hash_before) in worlds.iter().zip(&hashes_before) {
                    let before = images(w);
                    match w.apply(op.clone()) {
                        Ok(done) => {
                            prop_assert!(!invalid, "invalid edit accepted: {op:?}");
                            check_dirty(w, &before)?;
                            // Undo restores the prior hash; redo re-applies exactly.
                            let after = w.read().content_hash();
                            let redo = w.apply(EditOp::Restore(done.inverse)).unwrap();
                            prop_assert_eq!(w.read().content_hash(), *hash_before);
                            let again = w.apply(EditOp::Restore(redo.inverse)).unwrap();
                            prop_assert_eq!(w.read().content_hash(), after);
                            prop_assert_eq!(again.changed_voxels, done.changed_voxels);
                            w.take_dirty();
                            inverses.push(again.inverse);
                        }
                        Err(e) => {
                            prop_assert!(invalid, "valid edit rejected: {e} {op:?}");
                            prop_assert_eq!(w.read().content_hash(), *hash_before);
                        }
                    }
                }
                if !invalid {
                    reference.apply(op);
                    history.push((snapshot, inverses));
                }
            }
            Step::UndoLast => {
                let Some((snapshot, inverses)) = history.pop() else {
                    continue;
                };
                for (w, inv) in worlds.iter().zip(inverses) {
                    let before = images(w);
                    w.apply(EditOp::Restore(inv)).unwrap();
                    check_dirty(w, &before)?;
                }
                reference.voxels = snapshot;
            }
        }
        let hash = worlds[0].read().content_hash();
        for w in &worlds {
            check_contents(w, &reference)?;
            prop_assert_eq!(
                w.read().content_hash(),
                hash,
                "hash differs across worker counts"
            );
        }
    }
    // Removing everything frees every brick and every bucket.
    for w in &worlds {
        w.apply(EditOp::Shape {
            shape: Shape::Box {
                min: IVec3::ZERO,
                max: IVec3::new(71, 23, 39),
            },
            mode: Mode::Remove,
        })
        .unwrap();
        let v = w.read();
        v.validate().map_err(TestCaseError::fail)?;
        let m = v.memory();
        prop_assert_eq!(v.solid_count(), 0);
        prop_assert_eq!(m.bricks_used, 0);
        prop_assert_eq!(m.material_used, 0, "a bucket leaked");
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn edits_match_dense_reference(steps in prop::collection::vec(step(), 1..20)) {
        run_sequence(&steps)?;
    }
}

#[test]
fn bad_input_leaves_world_unchanged() {
    let w = new_world(2);
    w.apply(EditOp::Shape {
        shape: Shape::Sphere {
            centre: DVec3::splat(12.0),
            radius: 7.0,
        },
        mode: Mode::Add(1),
    })
    .unwrap();
    let hash = w.read().content_hash();
    let bad = [
        EditOp::Shape {
            shape: Shape::Voxel(IVec3::new(72, 0, 0)),
            mode: Mode::Add(0),
        },
        EditOp::Shape {
            shape: Shape::Voxel(IVec3::new(-1, 0, 0)),
            mode: Mode::Remove,
        },
        EditOp::Shape {
            shape: Shape::Sphere {
                centre: DVec3::ONE,
                radius: 0.0,
            },
            mode: Mode::Add(0),
        },
        EditOp::Shape {
            shape: Shape::Sphere {
                centre: DVec3::NAN,
                radius: 2.0,
            },
            mode: Mode::Add(0),
        },
        EditOp::Shape {
            shape: Shape::Sphere {
                centre: DVec3::ONE,
                radius: f64::INFINITY,
            },
            mode: Mode::Remove,
        },
        EditOp::Shape {
            shape: Shape::Box {
                min: IVec3::ONE,
                max: IVec3::ZERO,
            },
            mode: Mode::Add(0),
        },
        EditOp::Shape {
            shape: Shape::Sphere {
                centre: DVec3::ONE,
                radius: 3.0,
            },
            mode: Mode::Add(MATERIALS),
        },
        EditOp::Shape {
            shape: Shape::Sphere {
                centre: DVec3::ONE,
                radius: 3.0,
            },
            mode: Mode::Paint(200),
        },
        EditOp::Voxels(vec![
            VoxelEdit {
                pos: IVec3::ZERO,
                op: VoxelOp::Set(0),
            },
            VoxelEdit {
                pos: IVec3::new(0, 24, 0),
                op: VoxelOp::Set(0),
            },
        ]),
        EditOp::Voxels(vec![VoxelEdit {
            pos: IVec3::ZERO,
            op: VoxelOp::Set(99),
        }]),
    ];
    for op in bad {
        assert!(w.apply(op.clone()).is_err(), "{op:?} accepted");
        assert_eq!(w.read().content_hash(), hash, "{op:?} changed the world");
    }
    // A forged inverse with the wrong number of materials is refused.
    let mut inv = w
        .apply(EditOp::Shape {
            shape: Shape::Sphere {
                centre: DVec3::splat(12.0),
                radius: 5.0,
            },
            mode: Mode::Paint(2),
        })
        .unwrap()
        .inverse;
    let hash = w.read().content_hash();
    if let brickmap::PriorMaterials::PerVoxel(v) = &mut inv.bricks[0].prior {
        v.push(0);
    } else {
        inv.bricks[0].prior = brickmap::PriorMaterials::PerVoxel(vec![0; 600]);
    }
    assert!(w.apply(EditOp::Restore(inv)).is_err());
    assert_eq!(w.read().content_hash(), hash);
    // Shapes entirely outside the grid are clipped to nothing, not errors.
    let out = w
        .apply(EditOp::Shape {
            shape: Shape::Sphere {
                centre: DVec3::splat(-100.0),
                radius: 5.0,
            },
            mode: Mode::Add(0),
        })
        .unwrap();
    assert_eq!(out.changed_voxels, 0);
    // Grid sizes beyond the supported maximum are refused.
    assert!(GridDims::new(513, 1, 1).is_err());
}

#[test]
fn edits_from_many_threads_agree_with_sequential_order() {
    // Threads submit disjoint spheres concurrently: the result equals applying them in any
    // order, and the per-slab FIFO order keeps every slab consistent.
    let w = new_world(3);
    std::thread::scope(|s| {
        for t in 0..4 {
            let w = &w;
            s.spawn(move || {
                for k in 0..10 {
                    let centre = DVec3::new(8.0 + 16.0 * (t as f64), 12.0, 4.0 + 3.0 * k as f64);
                    w.apply(EditOp::Shape {
                        shape: Shape::Sphere {
                            centre,
                            radius: 3.0,
                        },
                        mode: Mode::Add(t as u8),
                    })
                    .unwrap();
                }
            });
        }
    });
    let seq = new_world(1);
    for t in 0..4 {
        for k in 0..10 {
            let centre = DVec3::new(8.0 + 16.0 * (t as f64), 12.0, 4.0 + 3.0 * k as f64);
            seq.apply(EditOp::Shape {
                shape: Shape::Sphere {
                    centre,
                    radius: 3.0,
                },
                mode: Mode::Add(t as u8),
            })
            .unwrap();
        }
    }
    w.read().validate().unwrap();
    assert_eq!(w.read().content_hash(), seq.read().content_hash());
}

#[test]
fn voxel_writes_into_full_cells() {
    // Whole bricks filled by a box are stored as full cells; single-voxel writes must turn
    // them back into stored bricks correctly (with every model check after each step).
    let inside = |i: i32, op: VoxelOp| VoxelEdit {
        pos: IVec3::new(8 + i % 16, 8 + i / 16 % 8, 8 + i / 128),
        op,
    };
    let steps = vec![
        Step::Edit(EditOp::Shape {
            shape: Shape::Box {
                min: IVec3::ZERO,
                max: IVec3::new(31, 23, 31),
            },
            mode: Mode::Add(2),
        }),
        Step::Edit(EditOp::Voxels(
            (0..40).map(|i| inside(i * 7, VoxelOp::Set(3))).collect(),
        )),
        Step::Edit(EditOp::Voxels(
            (0..40).map(|i| inside(i * 5 + 1, VoxelOp::Clear)).collect(),
        )),
        Step::Edit(EditOp::Voxels(vec![
            inside(300, VoxelOp::Paint(4)),
            inside(301, VoxelOp::Set(2)),
        ])),
        Step::Edit(EditOp::Shape {
            shape: Shape::Box {
                min: IVec3::new(16, 0, 0),
                max: IVec3::new(23, 23, 31),
            },
            mode: Mode::Paint(5),
        }),
        Step::Edit(EditOp::Voxels(vec![
            inside(9, VoxelOp::Set(2)),
            inside(200, VoxelOp::Clear),
        ])),
        Step::UndoLast,
        Step::Edit(EditOp::Shape {
            shape: Shape::Box {
                min: IVec3::ZERO,
                max: IVec3::new(31, 23, 31),
            },
            mode: Mode::Add(1),
        }),
        Step::Edit(EditOp::Voxels(vec![inside(0, VoxelOp::Clear)])),
        // Filling a whole brick voxel by voxel with one material makes it a full cell again.
        Step::Edit(EditOp::Shape {
            shape: Shape::Box {
                min: IVec3::new(40, 0, 0),
                max: IVec3::new(47, 7, 7),
            },
            mode: Mode::Remove,
        }),
        Step::Edit(EditOp::Voxels(
            (0..512)
                .map(|i| VoxelEdit {
                    pos: IVec3::new(40 + i % 8, i / 8 % 8, i / 64),
                    op: VoxelOp::Set(3),
                })
                .collect(),
        )),
        Step::Edit(EditOp::Voxels(
            (0..512)
                .map(|i| VoxelEdit {
                    pos: IVec3::new(40 + i % 8, i / 8 % 8, i / 64),
                    op: VoxelOp::Paint(4),
                })
                .collect(),
        )),
    ];
    run_sequence(&steps).unwrap();
}

#[test]
fn gpu_ranges_match_whole_images_and_flush_waits() {
    let w = new_world(3);
    // Queue several edits without waiting; flush returns once all are applied.
    let tickets: Vec<_> = (0..6)
        .map(|k| {
            let centre = DVec3::new(6.0 + 12.0 * k as f64, 12.0, 20.0);
            w.submit(EditOp::Shape {
                shape: Shape::Sphere {
                    centre,
                    radius: 7.0,
                },
                mode: Mode::Add(k as u8 % MATERIALS),
            })
            .unwrap()
        })
        .collect();
    w.flush().unwrap();
    let solid_after_flush = w.read().solid_count();
    let changed: u64 = tickets
        .into_iter()
        .map(|t| t.wait().unwrap().changed_voxels)
        .sum();
    assert_eq!(solid_after_flush, w.read().solid_count());
    assert!(changed >= solid_after_flush && solid_after_flush > 5000);
    w.apply(EditOp::Voxels(
        (0..500)
            .map(|i| VoxelEdit {
                pos: IVec3::new(i % 72, i % 24, i % 40),
                op: VoxelOp::Set((i % 5) as u8),
            })
            .collect(),
    ))
    .unwrap();
    let view = w.read();
    let mut seed = 7u64;
    for b in GpuBuffer::ALL {
        let whole = view.gpu_image(b);
        assert!(!whole.is_empty());
        for _ in 0..200 {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let a = (seed >> 33) % whole.len() as u64;
            let len = (seed >> 13) % 300;
            let range = a..(a + len).min(whole.len() as u64);
            let mut got = vec![0xAB];
            view.copy_gpu_range(b, range.clone(), &mut got);
            assert_eq!(
                &got[1..],
                &whole[range.start as usize..range.end as usize],
                "{b:?} {range:?}"
            );
        }
    }
}

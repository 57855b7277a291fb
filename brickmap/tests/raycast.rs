//! The ray cast against a brute-force reference on random and adversarial rays.
//!
//! The reference tests every solid voxel: under the half-open convention the ray point at t
//! lies in voxel ⌊o + t·d⌋, so the set of t ≥ 0 spent in voxel v is the intersection of one
//! interval per axis, [T(v), T(v+1)) for a positive component, (T(v+1), T(v)] for a negative
//! one, everything or nothing for a zero one, with T(b) = (b − o)/d computed in f64. The
//! first hit is the solid voxel whose set has the smallest infimum (a closed infimum before an
//! open one at the same t). The cast must return exactly that voxel and that t, and a normal
//! on an axis whose entry plane is crossed at that t (any of them at an edge or corner).

use brickmap::{EditOp, GridDims, Mode, Ray, Shape, VoxelEdit, VoxelOp, World, WorldConfig};
use glam::{DVec3, IVec3};

struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
    fn int(&mut self, n: u64) -> u64 {
        self.next() % n
    }
}

#[derive(Debug, Clone, Copy)]
struct Expected {
    voxel: IVec3,
    t: f64,
    open: bool,
}

/// Entry time and closedness per axis, and the exit, for voxel `v`.
fn interval(ray: &Ray, v: IVec3) -> Option<(f64, bool, f64, bool, [f64; 3])> {
    let (mut lo, mut lo_open, mut hi, mut hi_open) = (0.0f64, false, f64::INFINITY, false);
    let mut entry = [f64::NEG_INFINITY; 3];
    for i in 0..3 {
        let d = ray.dir[i];
        let (a, a_open, b, b_open) = if d > 0.0 {
            (
                ray.plane_time(i, v[i] as f64),
                false,
                ray.plane_time(i, v[i] as f64 + 1.0),
                true,
            )
        } else if d < 0.0 {
            (
                ray.plane_time(i, v[i] as f64 + 1.0),
                true,
                ray.plane_time(i, v[i] as f64),
                false,
            )
        } else if ray.origin[i].floor() == v[i] as f64 {
            continue;
        } else {
            return None;
        };
        entry[i] = a;
        if a > lo || (a == lo && a_open) {
            lo = a;
            lo_open = a_open;
        }
        if b < hi || (b == hi && b_open) {
            hi = b;
            hi_open = b_open;
        }
    }
    let nonempty = lo < hi || (lo == hi && !lo_open && !hi_open);
    nonempty.then_some((lo, lo_open, hi, hi_open, entry))
}

fn reference(solids: &[IVec3], ray: &Ray) -> Option<(Expected, [f64; 3])> {
    let mut best: Option<(Expected, [f64; 3])> = None;
    for &v in solids {
        if let Some((lo, open, _, _, entry)) = interval(ray, v) {
            let better = match &best {
                None => true,
                Some((b, _)) => lo < b.t || (lo == b.t && !open && b.open),
            };
            if better {
                best = Some((
                    Expected {
                        voxel: v,
                        t: lo,
                        open,
                    },
                    entry,
                ));
            }
        }
    }
    best
}

fn check(view: &brickmap::WorldView, dims: &GridDims, solids: &[IVec3], ray: &Ray) {
    let (near, shift) = ray.near_grid(dims);
    let want = reference(solids, &near);
    let got = view.ray_cast(ray, f64::INFINITY).unwrap().map(|(h, _)| h);
    match (want, got) {
        (None, None) => {}
        (Some((w, entry)), Some(g)) => {
            assert_eq!(
                g.voxel, w.voxel,
                "ray {ray:?}: voxel (reference t {}, got t {})",
                w.t, g.t
            );
            assert!(g.t.is_finite());
            assert_eq!(g.t, w.t + shift, "ray {ray:?}: t");
            let axis = (0..3).find(|&i| g.normal[i] != 0).expect("a normal");
            assert_eq!(g.normal.abs().element_sum(), 1);
            assert_eq!(
                g.normal[axis] as f64,
                -near.dir[axis].signum(),
                "ray {ray:?}: normal sign"
            );
            let latest = entry.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
            assert_eq!(
                entry[axis], latest,
                "ray {ray:?}: normal {} is not an entry face",
                g.normal
            );
        }
        (w, g) => panic!("ray {ray:?}: reference {w:?}, cast {g:?}"),
    }
}

/// A 96×32×96 world (3×1×3 coarse cells) with clusters and scattered voxels.
fn scene(seed: u64) -> (World, Vec<IVec3>) {
    let dims = GridDims::new(12, 4, 12).unwrap();
    let world = World::new(dims, WorldConfig::with_workers(2)).unwrap();
    let mut rng = Rng(seed);
    world
        .apply(EditOp::Shape {
            shape: Shape::Sphere {
                centre: DVec3::new(20.0, 10.0, 70.0),
                radius: 5.0,
            },
            mode: Mode::Add(0),
        })
        .unwrap();
    world
        .apply(EditOp::Shape {
            shape: Shape::Box {
                min: IVec3::new(60, 0, 8),
                max: IVec3::new(71, 7, 15),
            },
            mode: Mode::Add(0),
        })
        .unwrap();
    let mut edits = Vec::new();
    for _ in 0..400 {
        let p = IVec3::new(rng.int(96) as i32, rng.int(32) as i32, rng.int(96) as i32);
        edits.push(VoxelEdit {
            pos: p,
            op: VoxelOp::Set(0),
        });
    }
    // Voxels on the grid's faces, edges and corners.
    for c in [
        IVec3::ZERO,
        IVec3::new(95, 31, 95),
        IVec3::new(95, 0, 0),
        IVec3::new(0, 31, 95),
        IVec3::new(47, 0, 95),
    ] {
        edits.push(VoxelEdit {
            pos: c,
            op: VoxelOp::Set(0),
        });
    }
    world.apply(EditOp::Voxels(edits)).unwrap();
    let view = world.read();
    let mut solids = Vec::new();
    for z in 0..96 {
        for y in 0..32 {
            for x in 0..96 {
                if view.voxel(IVec3::new(x, y, z)).unwrap().is_some() {
                    solids.push(IVec3::new(x, y, z));
                }
            }
        }
    }
    drop(view);
    (world, solids)
}

fn random_dir(rng: &mut Rng) -> DVec3 {
    loop {
        let d = DVec3::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        );
        if d.length_squared() > 1e-6 {
            return d.normalize();
        }
    }
}

#[test]
fn random_rays_match_reference() {
    let (world, solids) = scene(0x9e3779b97f4a7c15);
    let dims = world.dims();
    let view = world.read();
    let mut rng = Rng(12345);
    for _ in 0..100_000 {
        let origin = DVec3::new(
            rng.range(-40.0, 136.0),
            rng.range(-40.0, 72.0),
            rng.range(-40.0, 136.0),
        );
        check(
            &view,
            &dims,
            &solids,
            &Ray {
                origin,
                dir: random_dir(&mut rng),
            },
        );
    }
}

/// Directions that make ties: axis-parallel with ±0.0, edge and space diagonals, tiny and
/// denormal components, grazing.
fn special_dir(rng: &mut Rng) -> DVec3 {
    let pick = |rng: &mut Rng| -> f64 {
        let s = if rng.int(2) == 0 { 1.0 } else { -1.0 };
        match rng.int(9) {
            0 => 0.0,
            1 => -0.0,
            2 => s,
            3 => s * 1e-20,
            4 => s * 5e-324,
            5 => s * f64::MIN_POSITIVE,
            6 => s * 0.5,
            7 => s * 1e-9,
            _ => s * rng.range(0.0, 1.0),
        }
    };
    loop {
        let d = DVec3::new(pick(rng), pick(rng), pick(rng));
        if d != DVec3::ZERO {
            return d;
        }
    }
}

/// Origins on voxel, brick, coarse and grid planes, edges and corners; inside solid voxels;
/// outside the grid; far away.
fn special_origin(rng: &mut Rng, solids: &[IVec3]) -> DVec3 {
    let lattice = |rng: &mut Rng, n: f64| -> f64 {
        let grid_step = [1.0, 8.0, 32.0][rng.int(3) as usize];
        let v = (rng.range(-1.0, n / grid_step + 1.0)).floor() * grid_step;
        match rng.int(4) {
            0 => v,
            1 => v + 0.5,
            2 => v + rng.unit(),
            _ => v - 1e-12,
        }
    };
    match rng.int(6) {
        0 => {
            solids[rng.int(solids.len() as u64) as usize].as_dvec3()
                + DVec3::new(rng.unit(), rng.unit(), rng.unit())
        }
        1 => solids[rng.int(solids.len() as u64) as usize].as_dvec3(),
        2 => DVec3::new(
            rng.range(-3e7, 3e7),
            rng.range(-3e7, 3e7),
            rng.range(-3e7, 3e7),
        ),
        _ => DVec3::new(lattice(rng, 96.0), lattice(rng, 32.0), lattice(rng, 96.0)),
    }
}

#[test]
fn adversarial_rays_match_reference() {
    let (world, solids) = scene(77);
    let dims = world.dims();
    let view = world.read();
    let mut rng = Rng(987654321);
    for _ in 0..150_000 {
        let origin = special_origin(&mut rng, &solids);
        let mut dir = special_dir(&mut rng);
        if rng.int(4) == 0 {
            // Aim through a voxel corner or edge of a solid voxel.
            let target = solids[rng.int(solids.len() as u64) as usize].as_dvec3()
                + DVec3::new(
                    rng.int(2) as f64,
                    rng.int(2) as f64,
                    rng.int(2) as f64 * 0.5,
                );
            let d = target - origin;
            if d != DVec3::ZERO {
                dir = d;
            }
        }
        check(&view, &dims, &solids, &Ray { origin, dir });
    }
}

#[test]
fn exact_diagonals_and_axes_through_lattice_points() {
    let (world, solids) = scene(5);
    let dims = world.dims();
    let view = world.read();
    let mut n = 0;
    for d in [
        DVec3::new(1.0, 1.0, 0.0),
        DVec3::new(1.0, -1.0, 0.0),
        DVec3::new(-1.0, 1.0, 1.0),
        DVec3::new(1.0, 1.0, 1.0),
        DVec3::new(0.0, -1.0, -0.0),
        DVec3::new(-0.0, 0.0, 1.0),
        DVec3::new(-1.0, -0.0, 0.0),
        DVec3::new(2.0, -2.0, 1.0),
        DVec3::new(1.0, 2.0, -2.0),
    ] {
        for x in (-2..98).step_by(3) {
            for y in (-2..34).step_by(2) {
                for z in [-1, 0, 7, 8, 31, 32, 33, 64, 95, 96] {
                    let origin = IVec3::new(x, y, z).as_dvec3();
                    check(&view, &dims, &solids, &Ray { origin, dir: d });
                    check(
                        &view,
                        &dims,
                        &solids,
                        &Ray {
                            origin: origin + 0.5,
                            dir: d,
                        },
                    );
                    n += 2;
                }
            }
        }
    }
    assert!(n > 100_000, "{n} rays");
}

#[test]
fn largest_grid_far_corner() {
    let dims = GridDims::new(512, 128, 512).unwrap();
    let world = World::new(dims, WorldConfig::with_workers(2)).unwrap();
    let far = IVec3::new(4095, 1023, 4095);
    let solids = vec![
        far,
        far - IVec3::new(3, 0, 0),
        far - IVec3::new(0, 9, 40),
        IVec3::new(4000, 1000, 4090),
    ];
    world
        .apply(EditOp::Voxels(
            solids
                .iter()
                .map(|&pos| VoxelEdit {
                    pos,
                    op: VoxelOp::Set(0),
                })
                .collect(),
        ))
        .unwrap();
    let view = world.read();
    let mut rng = Rng(4242);
    for _ in 0..20_000 {
        let target =
            solids[rng.int(4) as usize].as_dvec3() + DVec3::new(rng.unit(), rng.unit(), rng.unit());
        let origin = match rng.int(3) {
            0 => target + random_dir(&mut rng) * rng.range(1.0, 200.0),
            1 => DVec3::new(4096.0, rng.range(990.0, 1030.0), 4096.0),
            _ => target + random_dir(&mut rng) * rng.range(1e3, 1e8),
        };
        let mut dir = target - origin;
        if rng.int(3) == 0 {
            dir = special_dir(&mut rng);
        }
        if dir == DVec3::ZERO {
            continue;
        }
        check(&view, &dims, &solids, &Ray { origin, dir });
    }
}

#[test]
fn invalid_rays_are_errors() {
    let (world, _) = scene(1);
    let view = world.read();
    for ray in [
        Ray {
            origin: DVec3::ZERO,
            dir: DVec3::ZERO,
        },
        Ray {
            origin: DVec3::NAN,
            dir: DVec3::X,
        },
        Ray {
            origin: DVec3::ZERO,
            dir: DVec3::new(f64::INFINITY, 0.0, 0.0),
        },
    ] {
        assert!(view.ray_cast(&ray, f64::INFINITY).is_err(), "{ray:?}");
    }
    assert!(
        view.ray_cast(
            &Ray {
                origin: DVec3::ZERO,
                dir: DVec3::X
            },
            f64::NAN
        )
        .is_err()
    );
}

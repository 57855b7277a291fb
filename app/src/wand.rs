//! Selections made as voxel sets: the magic wand (the voxels connected to a clicked one that
//! have its material, or that are solid; connected by faces, or also by edges and corners),
//! the face wand (the connected coplanar region of a clicked face: the voxels of its layer
//! whose face on that side is exposed, joined in the plane through edges, or also corners),
//! every voxel of a material, and how a new set combines with the selection (replace; Shift
//! adds, Ctrl takes away, Shift + Ctrl keeps what both hold).

use brickmap::{BrickMaterials, Mask, VoxelSet, WorldView};
use glam::{IVec3, UVec3};
use serde::{Deserialize, Serialize};
use std::collections::{HashMap, HashSet, VecDeque};

/// How a new set of voxels changes the selection.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Combine {
    /// It becomes the selection.
    #[default]
    Replace,
    /// It is added.
    Add,
    /// It is taken away.
    Subtract,
    /// Only what both hold stays.
    Intersect,
}

impl Combine {
    /// What the modifiers held say: Shift adds, Ctrl takes away, both intersect.
    pub fn of(shift: bool, ctrl: bool) -> Self {
        match (shift, ctrl) {
            (true, true) => Combine::Intersect,
            (true, false) => Combine::Add,
            (false, true) => Combine::Subtract,
            (false, false) => Combine::Replace,
        }
    }

    /// `set` combined with the current selection's voxels.
    pub fn apply(self, current: Option<&VoxelSet>, set: VoxelSet) -> VoxelSet {
        let empty = VoxelSet::new();
        let current = current.unwrap_or(&empty);
        match self {
            Combine::Replace => set,
            Combine::Add => current.union(&set),
            Combine::Subtract => current.difference(&set),
            Combine::Intersect => current.intersection(&set),
        }
    }
}

/// The magic wand from `start`: the connected voxels that share its material (`by_material`)
/// or are solid, joined through faces (and with `diagonal` through edges and corners too).
/// Empty when `start` is empty or outside the grid.
///
/// A flood a brick at a time: the voxels a brick may take (solid, of the material) as a
/// mask, grown inside the brick by whole-mask shifts until nothing changes, and what reaches
/// a side handed to the brick beyond it as seeds.
pub fn wand(view: &WorldView<'_>, start: IVec3, by_material: bool, diagonal: bool) -> VoxelSet {
    let Ok(Some(material)) = view.voxel(start) else {
        return VoxelSet::new();
    };
    let bricks = view.dims().bricks().as_ivec3();
    let mut allowed: HashMap<UVec3, Mask> = HashMap::new();
    let mut allow = |b: UVec3| {
        *allowed.entry(b).or_insert_with(|| {
            let (mask, dense) = view.brick_voxels(b);
            if !by_material {
                return mask;
            }
            let mut m = Mask::EMPTY;
            for bit in mask.ones() {
                if dense[bit] == material {
                    m.set(bit);
                }
            }
            m
        })
    };
    let mut filled: HashMap<UVec3, Mask> = HashMap::new();
    let l = start.rem_euclid(IVec3::splat(8));
    let mut seed = Mask::EMPTY;
    seed.set((l.x + 8 * l.y + 64 * l.z) as usize);
    let mut queue = VecDeque::from([((start / 8).as_uvec3(), seed)]);
    // The brick offsets a flood crosses to.
    let offsets: Vec<IVec3> = (0..27)
        .map(|d| IVec3::new(d % 3 - 1, d / 3 % 3 - 1, d / 9 - 1))
        .filter(|d| *d != IVec3::ZERO && (diagonal || d.abs().element_sum() == 1))
        .collect();
    while let Some((b, seeds)) = queue.pop_front() {
        let can = allow(b);
        let had = filled.get(&b).copied().unwrap_or(Mask::EMPTY);
        let new = seeds.and(&can).and_not(&had);
        if new.is_empty() {
            continue;
        }
        let mut now = had.or(&new);
        loop {
            let next = now.or(&grow(&now, [true; 3], diagonal).and(&can));
            if next == now {
                break;
            }
            now = next;
        }
        let added = now.and_not(&had);
        filled.insert(b, now);
        for d in &offsets {
            let n = b.as_ivec3() + *d;
            if n.cmplt(IVec3::ZERO).any() || n.cmpge(bricks).any() {
                continue;
            }
            // Along the axes the step crosses: the far side lands on the near one; along the
            // others (26-connected only) a neighbour may sit one voxel over.
            let along = [d.x == 0, d.y == 0, d.z == 0];
            let spread = if diagonal {
                grow(&added, along, true)
            } else {
                added
            };
            let reached = spread.shifted(*d * -7);
            if !reached.is_empty() {
                queue.push_back((n.as_uvec3(), reached));
            }
        }
    }
    let mut out = VoxelSet::new();
    for (b, m) in filled {
        out.set_brick(b, m);
    }
    out
}

/// `m` and its voxels' neighbours inside the brick along the axes `along` says: one voxel
/// either way on each (through faces), or with `diagonal` the whole 3 × 3 × 3 block over them.
fn grow(m: &Mask, along: [bool; 3], diagonal: bool) -> Mask {
    let axes = [IVec3::X, IVec3::Y, IVec3::Z];
    if diagonal {
        let mut out = *m;
        for (a, on) in axes.iter().zip(along) {
            if on {
                out = out.or(&out.shifted(*a)).or(&out.shifted(-*a));
            }
        }
        out
    } else {
        let mut out = *m;
        for (a, on) in axes.iter().zip(along) {
            if on {
                out = out.or(&m.shifted(*a)).or(&m.shifted(-*a));
            }
        }
        out
    }
}

/// Every voxel of material `material`.
pub fn of_material(view: &WorldView<'_>, material: u8) -> VoxelSet {
    let mut out = VoxelSet::new();
    view.for_each_brick(|b, mask, mats| {
        let m = match mats {
            BrickMaterials::Uniform(u) if u == material => *mask,
            BrickMaterials::Uniform(_) => Mask::EMPTY,
            BrickMaterials::PerVoxel(_) => {
                let mut m = Mask::EMPTY;
                for (k, bit) in mask.ones().enumerate() {
                    if mats.at(k) == material {
                        m.set(bit);
                    }
                }
                m
            }
        };
        out.set_brick(b, m);
    });
    out
}

/// The voxels of the plane through `start` across `normal` (one axis, ±1), joined through
/// edges in the plane (with `diagonal` also through corners), that `takes` accepts and that
/// lie in `lo..hi` (hi exclusive); sorted by x, then y, then z. Extrude, plane fill and the
/// face wand flood this way.
pub fn plane_flood(
    start: IVec3,
    normal: IVec3,
    (lo, hi): (IVec3, IVec3),
    diagonal: bool,
    takes: impl Fn(IVec3) -> bool,
) -> Vec<IVec3> {
    let inside = |v: IVec3| v.cmpge(lo).all() && v.cmplt(hi).all();
    if !inside(start) || !takes(start) {
        return Vec::new();
    }
    // The in-plane steps: 4 through edges, 8 with the corners.
    let axes: Vec<IVec3> = [IVec3::X, IVec3::Y, IVec3::Z]
        .into_iter()
        .filter(|a| a.dot(normal) == 0)
        .collect();
    let mut steps: Vec<IVec3> = axes.iter().flat_map(|a| [*a, -*a]).collect();
    if diagonal {
        for i in [-1, 1] {
            for j in [-1, 1] {
                steps.push(axes[0] * i + axes[1] * j);
            }
        }
    }
    let mut seen = HashSet::from([start]);
    let mut stack = vec![start];
    let mut out = Vec::new();
    while let Some(v) = stack.pop() {
        out.push(v);
        for s in &steps {
            let n = v + *s;
            if inside(n) && !seen.contains(&n) && takes(n) {
                seen.insert(n);
                stack.push(n);
            }
        }
    }
    out.sort_by_key(|v| (v.x, v.y, v.z));
    out
}

/// The face wand from the face of `start` facing `normal`: the solid voxels of its layer
/// whose neighbour along `normal` is empty (or outside the grid), joined in the plane
/// ([`plane_flood`]); with `by_material` only those of `start`'s material. Empty when that
/// face is not exposed or `normal` is not a face's.
pub fn face_region(
    view: &WorldView<'_>,
    start: IVec3,
    normal: IVec3,
    by_material: bool,
    diagonal: bool,
) -> VoxelSet {
    let mut set = VoxelSet::new();
    if normal.abs().element_sum() != 1 {
        return set;
    }
    let at = |v: IVec3| view.voxel(v).ok().flatten();
    let Some(material) = at(start) else {
        return set;
    };
    let exposed =
        |v: IVec3| at(v).is_some_and(|m| !by_material || m == material) && at(v + normal).is_none();
    let grid = (IVec3::ZERO, view.dims().voxels());
    for v in plane_flood(start, normal, grid, diagonal, exposed) {
        set.insert(v);
    }
    set
}

//! Selections made as voxel sets: the magic wand (the voxels connected to a clicked one that
//! have its material, or that are solid; connected by faces, or also by edges and corners),
//! every voxel of a material, and how a new set combines with the selection (replace; Shift
//! adds, Ctrl takes away, Shift + Ctrl keeps what both hold).

use brickmap::{BrickMaterials, Mask, VoxelSet, WorldView};
use glam::{IVec3, UVec3};
use serde::{Deserialize, Serialize};
use std::collections::HashMap;

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
pub fn wand(view: &WorldView<'_>, start: IVec3, by_material: bool, diagonal: bool) -> VoxelSet {
    let Ok(Some(material)) = view.voxel(start) else {
        return VoxelSet::new();
    };
    let takes = |v: IVec3| match view.voxel(v) {
        Ok(Some(m)) => !by_material || m == material,
        _ => false,
    };
    let steps: Vec<IVec3> = (0..27)
        .map(|d| IVec3::new(d % 3 - 1, d / 3 % 3 - 1, d / 9 - 1))
        .filter(|d| *d != IVec3::ZERO && (diagonal || d.abs().element_sum() == 1))
        .collect();
    let mut masks: HashMap<UVec3, Mask> = HashMap::new();
    let mut seen = |v: IVec3| {
        let l = v.rem_euclid(IVec3::splat(8));
        let bit = (l.x + 8 * l.y + 64 * l.z) as usize;
        let m = masks.entry((v / 8).as_uvec3()).or_insert(Mask::EMPTY);
        let was = m.get(bit);
        m.set(bit);
        was
    };
    seen(start);
    let mut stack = vec![start];
    while let Some(v) = stack.pop() {
        for d in &steps {
            let n = v + *d;
            if takes(n) && !seen(n) {
                stack.push(n);
            }
        }
    }
    let mut out = VoxelSet::new();
    for (b, m) in masks {
        out.set_brick(b, m);
    }
    out
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

//! Emissive voxels as lights: every exposed face of an emissive voxel, in a light tree the
//! renderers sample from (CPU reference and GPU alike, from the same bytes).
//!
//! A *light face* is a face of a voxel whose material is emissive with positive weight, whose
//! neighbour across the face is inside the grid and empty. Those are exactly the emissive
//! faces a ray travelling in air can reach (a face towards a solid or dielectric neighbour is
//! seen only from inside that neighbour, where no light is sampled; one on the grid's outer
//! boundary only from outside the grid, where no vertex is). A face's weight is its
//! material's: (r + g + b) × strength of the linear emitted radiance, faces being unit squares.
//!
//! Layout (the GPU region [`crate::GpuBuffer::Lights`], little-endian words):
//! - header: capacity C (a power of two), light faces, 0, 0;
//! - 256 f32 material weights (0 for materials that are not lights);
//! - 2C f32 tree nodes: node 1 the root (total weight), node i's children 2i and 2i + 1,
//!   leaves C..2C (slot s at C + s holds its face's weight, 0 when free); node 0 unused;
//! - 2C node bounds of four words (`tree`): lo.x | hi.x << 16, lo.y | hi.y << 16,
//!   lo.z | hi.z << 16 (voxels, inclusive) and the mask of face directions below the node;
//! - C face records of two words: x | z << 12 | face << 24, and y | material << 16, with face
//!   0..6 = −x, +x, −y, +y, −z, +z;
//! - 2C words of the face → slot table (`lookup`).
//!
//! A shading point descends the tree by importance (`tree`): near faces that face it are
//! chosen more often than far ones or ones facing away. Faces take slots in the Morton order of
//! their bricks, so a subtree gathers nearby faces and its bounds are tight.
//!
//! Kept exact under edits: after an edit the world recomputes the faces of the bricks it
//! changed and of their face neighbours that hold lit voxels ([`Lights::apply`]); a brick
//! whose faces did not change writes nothing. Each changed leaf rewrites its ancestors (each
//! the sum and union of its two children, so the tree is a function of its leaves) and its
//! table entries: an edit costs its bricks and log C nodes per changed face, never anything
//! proportional to the scene. Faces an edit adds take free slots, wherever those lie: the tree
//! stays exact, its bounds may loosen until the next rescan (loading, a material becoming a
//! light).

pub mod lookup;
pub mod tree;

use crate::brick::{BrickMaterials, Mask};
use crate::dirty::DirtyRanges;
use crate::grid::GridDims;
use crate::material::{MaterialKind, MaterialTable};
use glam::{IVec3, UVec3};
use std::collections::{HashMap, HashSet};
use std::ops::Range;

/// Words of the header.
pub const HEADER_WORDS: u64 = 4;
/// Byte offset of the material weights.
pub const WEIGHTS_OFFSET: u64 = HEADER_WORDS * 4;
/// Byte offset of the tree nodes.
pub const NODES_OFFSET: u64 = WEIGHTS_OFFSET + 256 * 4;

/// Outward normals of faces 0..6.
pub const FACE_NORMALS: [IVec3; 6] = [
    IVec3::NEG_X,
    IVec3::X,
    IVec3::NEG_Y,
    IVec3::Y,
    IVec3::NEG_Z,
    IVec3::Z,
];

/// One light face, unpacked.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LightFace {
    /// The emissive voxel.
    pub voxel: IVec3,
    /// Which face (index into [`FACE_NORMALS`]).
    pub face: u8,
    /// The voxel's material.
    pub material: u8,
}

impl LightFace {
    fn pack(self) -> [u32; 2] {
        [
            self.voxel.x as u32 | (self.voxel.z as u32) << 12 | (self.face as u32) << 24,
            self.voxel.y as u32 | (self.material as u32) << 16,
        ]
    }
    fn unpack(w: [u32; 2]) -> Self {
        Self {
            voxel: IVec3::new(
                (w[0] & 0xFFF) as i32,
                (w[1] & 0xFFFF) as i32,
                ((w[0] >> 12) & 0xFFF) as i32,
            ),
            face: ((w[0] >> 24) & 7) as u8,
            material: (w[1] >> 16) as u8,
        }
    }
    /// The face's outward normal.
    pub fn normal(&self) -> IVec3 {
        FACE_NORMALS[self.face as usize]
    }
}

/// The weight of every material: (r + g + b) × strength of its linear emitted radiance for
/// emissive ones, 0 for the rest.
pub fn material_weights(table: &MaterialTable) -> [f32; 256] {
    let mut w = [0f32; 256];
    for (i, slot) in w.iter_mut().enumerate().take(table.len()) {
        let Ok(m) = table.get(i as u8) else { continue };
        if m.kind != MaterialKind::Emissive {
            continue;
        }
        let strength = table.param(m.kind, m.param).unwrap_or(0.0) as f64;
        let rgb: f64 = table
            .colour(m.colour)
            .iter()
            .map(|&c| srgb_to_linear(c))
            .sum();
        let weight = (rgb * strength) as f32;
        *slot = if weight.is_finite() && weight > 0.0 {
            weight
        } else {
            0.0
        };
    }
    w
}

/// sRGB-encoded byte to linear (the renderers' albedo decoding).
pub fn srgb_to_linear(c: u8) -> f64 {
    let c = c as f64 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// A brick's recomputed lights: whether it holds lit voxels, and its light faces in voxel
/// then face order.
pub(crate) struct BrickLights {
    cell: u32,
    /// Morton code of the brick (the order its new faces take slots in).
    morton: u64,
    lit: bool,
    faces: Vec<[u32; 2]>,
}

/// The light faces of a world, as a sum tree by weight.
#[derive(Clone, Debug)]
pub struct Lights {
    capacity: u32,
    nodes: Vec<f32>,
    /// Each node's bounds (`tree`): 2C entries like `nodes`.
    bounds: Vec<[u32; 4]>,
    faces: Vec<[u32; 2]>,
    table: lookup::FaceTable,
    weights: [f32; 256],
    /// Slots of each brick cell's faces, in its face order.
    slots: HashMap<u32, Vec<u32>>,
    /// Brick cells holding a voxel of a lit material (their faces may change when a
    /// neighbour does).
    lit_cells: HashSet<u32>,
    free: Vec<u32>,
    used: u32,
    count: u32,
    dirty: DirtyRanges,
}

impl Default for Lights {
    fn default() -> Self {
        Self {
            capacity: 1,
            nodes: vec![0.0; 2],
            bounds: vec![tree::EMPTY_BOUNDS; 2],
            faces: vec![[0, 0]; 1],
            table: lookup::FaceTable::with_len(2),
            weights: [0.0; 256],
            slots: HashMap::new(),
            lit_cells: HashSet::new(),
            free: Vec::new(),
            used: 0,
            count: 0,
            dirty: DirtyRanges::default(),
        }
    }
}

impl Lights {
    /// Light faces.
    pub fn len(&self) -> u32 {
        self.count
    }
    /// Whether there is no light face (nothing to sample).
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }
    /// Total weight (the root), 0 when empty.
    pub fn total(&self) -> f32 {
        self.nodes[1]
    }
    /// Whether any material is a light (weight > 0).
    pub fn any_lit_material(&self) -> bool {
        self.weights.iter().any(|&w| w > 0.0)
    }
    /// The weight of a material (0 when it is not a light).
    pub fn weight(&self, material: u8) -> f32 {
        self.weights[material as usize]
    }
    /// Leaf slots (a power of two).
    pub fn capacity(&self) -> u32 {
        self.capacity
    }
    /// The face in a slot (only meaningful for a slot with a positive leaf).
    pub fn face(&self, slot: u32) -> LightFace {
        LightFace::unpack(self.faces[slot as usize])
    }
    /// The weight of a slot's leaf.
    pub fn leaf(&self, slot: u32) -> f32 {
        self.nodes[(self.capacity + slot) as usize]
    }
    /// The slot of the light face of `voxel` in direction `face`, if it is one.
    pub fn slot_of(&self, voxel: IVec3, face: u8) -> Option<u32> {
        let [w0, w1] = LightFace {
            voxel,
            face,
            material: 0,
        }
        .pack();
        self.table.find(&self.faces, w0, w1)
    }
    /// Every light face with its slot.
    pub fn iter(&self) -> impl Iterator<Item = (u32, LightFace)> + '_ {
        self.slots.values().flatten().map(|&s| (s, self.face(s)))
    }

    /// The slot whose leaf holds `u` ∈ [0, 1) of the total weight, descending from the root
    /// (a child of weight 0 is never entered); None when empty. Its probability is
    /// leaf / total. The GPU descends the same way (shaders/lights.glsl).
    pub fn sample(&self, u: f64) -> Option<u32> {
        let total = self.total();
        if total <= 0.0 {
            return None;
        }
        let mut x = (u * total as f64) as f32;
        let mut i = 1usize;
        let c = self.capacity as usize;
        while i < c {
            let (l, r) = (self.nodes[2 * i], self.nodes[2 * i + 1]);
            if (x < l && l > 0.0) || r <= 0.0 {
                i *= 2;
            } else {
                x -= l;
                i = 2 * i + 1;
            }
        }
        Some((i - c) as u32)
    }

    /// Size of the GPU image in bytes.
    pub fn gpu_size(&self) -> u64 {
        self.table_offset() + self.capacity as u64 * 8
    }

    fn bounds_offset(&self) -> u64 {
        NODES_OFFSET + self.capacity as u64 * 8
    }

    fn faces_offset(&self) -> u64 {
        self.bounds_offset() + self.capacity as u64 * 32
    }

    fn table_offset(&self) -> u64 {
        self.faces_offset() + self.capacity as u64 * 8
    }

    /// The bytes `range` of the GPU image into `dst` (which holds `range`).
    pub fn copy_range(&self, range: &Range<u64>, dst: &mut [u8]) {
        let header = [self.capacity, self.count, 0, 0];
        let parts: [(&[u8], u64); 6] = [
            (bytemuck::cast_slice(&header), 0),
            (bytemuck::cast_slice(&self.weights), WEIGHTS_OFFSET),
            (bytemuck::cast_slice(&self.nodes), NODES_OFFSET),
            (bytemuck::cast_slice(&self.bounds), self.bounds_offset()),
            (bytemuck::cast_slice(&self.faces), self.faces_offset()),
            (
                bytemuck::cast_slice(&self.table.entries),
                self.table_offset(),
            ),
        ];
        for (src, at) in parts {
            let lo = at.max(range.start);
            let hi = (at + src.len() as u64).min(range.end);
            if lo < hi {
                dst[(lo - range.start) as usize..(hi - range.start) as usize]
                    .copy_from_slice(&src[(lo - at) as usize..(hi - at) as usize]);
            }
        }
    }

    /// Takes the byte ranges changed since the last call.
    pub fn take_dirty(&mut self) -> Vec<Range<u64>> {
        self.dirty.take()
    }

    fn mark_all_dirty(&mut self) {
        self.dirty.record(0..self.gpu_size());
    }

    /// Sets the material weights from a table. Returns whether the set of lit materials
    /// changed (then every brick must be rescanned: [`Lights::rebuild`]); otherwise leaves
    /// whose material's weight changed are rewritten here (cost: the light faces).
    pub(crate) fn set_weights(&mut self, weights: [f32; 256]) -> bool {
        if weights == self.weights {
            return false;
        }
        let lit_changed = (0..256).any(|i| (weights[i] > 0.0) != (self.weights[i] > 0.0));
        self.weights = weights;
        self.dirty.record(WEIGHTS_OFFSET..WEIGHTS_OFFSET + 256 * 4);
        if lit_changed {
            return true;
        }
        let c = self.capacity as usize;
        let mut changed = false;
        for slot in self.slots.values().flatten() {
            let w = self.weights[self.face(*slot).material as usize];
            let leaf = &mut self.nodes[c + *slot as usize];
            if *leaf != w {
                *leaf = w;
                changed = true;
            }
        }
        if changed {
            self.rebuild_nodes();
            self.dirty
                .record(NODES_OFFSET..NODES_OFFSET + 8 * self.capacity as u64);
        }
        false
    }

    /// Forgets every face (before a full rescan), keeping the weights.
    pub(crate) fn clear(&mut self) {
        let weights = self.weights;
        *self = Self {
            weights,
            dirty: std::mem::take(&mut self.dirty),
            ..Self::default()
        };
        self.mark_all_dirty();
    }

    /// Whether a brick cell holds lit voxels.
    pub(crate) fn is_lit_cell(&self, cell: u32) -> bool {
        self.lit_cells.contains(&cell)
    }

    /// Puts recomputed bricks in: a brick whose faces are unchanged writes nothing; the
    /// others reuse their slots, free the extra ones or take free ones (bricks in Morton
    /// order), and rewrite their leaves, the leaves' ancestors and their table entries.
    pub(crate) fn apply(&mut self, mut bricks: Vec<BrickLights>) {
        bricks.sort_by_key(|b| b.morton);
        let mut changed_bricks = Vec::new();
        let mut entries = Vec::new();
        for b in bricks {
            if b.lit {
                self.lit_cells.insert(b.cell);
            } else {
                self.lit_cells.remove(&b.cell);
            }
            let old = self.slots.remove(&b.cell).unwrap_or_default();
            if old.len() == b.faces.len()
                && old
                    .iter()
                    .zip(&b.faces)
                    .all(|(s, f)| self.faces[*s as usize] == *f)
            {
                if !old.is_empty() {
                    self.slots.insert(b.cell, old);
                }
                continue;
            }
            // Out of the table while every face record is still the one it was entered with.
            // (Their records are cleared at once: a growth rebuilds the table from the
            // records written.)
            for &s in &old {
                self.table.remove(&self.faces, s, &mut entries);
                self.faces[s as usize] = [0, 0];
            }
            changed_bricks.push((b.cell, old, b.faces));
        }
        let mut touched: Vec<u32> = Vec::new();
        for (cell, old, faces) in changed_bricks {
            let mut mine = Vec::with_capacity(faces.len());
            let mut old = old.into_iter();
            for f in faces {
                let slot = match old.next() {
                    Some(s) => s,
                    None => self.take_slot(&mut entries),
                };
                self.faces[slot as usize] = f;
                let face = LightFace::unpack(f);
                let leaf = (self.capacity + slot) as usize;
                self.nodes[leaf] = self.weights[face.material as usize];
                self.bounds[leaf] = tree::leaf_bounds(face);
                entries.push(self.table.insert(&self.faces, slot));
                touched.push(slot);
                mine.push(slot);
            }
            for s in old {
                self.faces[s as usize] = [0, 0];
                let leaf = (self.capacity + s) as usize;
                self.nodes[leaf] = 0.0;
                self.bounds[leaf] = tree::EMPTY_BOUNDS;
                self.free.push(s);
                self.count -= 1;
                touched.push(s);
            }
            if !mine.is_empty() {
                self.slots.insert(cell, mine);
            }
        }
        if touched.is_empty() {
            return;
        }
        self.dirty.record(0..8); // capacity and count
        let (faces_at, bounds_at, table_at) = (
            self.faces_offset(),
            self.bounds_offset(),
            self.table_offset(),
        );
        let c = self.capacity;
        touched.sort_unstable();
        touched.dedup();
        for &s in &touched {
            self.dirty
                .record(faces_at + s as u64 * 8..faces_at + s as u64 * 8 + 8);
        }
        entries.sort_unstable();
        entries.dedup();
        for e in entries {
            let at = table_at + e as u64 * 4;
            self.dirty.record(at..at + 4);
        }
        // Ancestors, level by level: each the sum and union of its children.
        let mut level: Vec<u32> = touched.iter().map(|s| c + s).collect();
        loop {
            for &i in &level {
                let at = NODES_OFFSET + i as u64 * 4;
                self.dirty.record(at..at + 4);
                let at = bounds_at + i as u64 * 16;
                self.dirty.record(at..at + 16);
            }
            if level.first().is_none_or(|&i| i <= 1) {
                break;
            }
            let mut parents: Vec<u32> = level.iter().map(|i| i / 2).collect();
            parents.dedup();
            for &p in &parents {
                self.set_node(p as usize);
            }
            level = parents;
        }
    }

    /// Node `i` from its children.
    fn set_node(&mut self, i: usize) {
        self.nodes[i] = self.nodes[2 * i] + self.nodes[2 * i + 1];
        self.bounds[i] = tree::union(self.bounds[2 * i], self.bounds[2 * i + 1]);
    }

    /// A free slot, growing the capacity when none is left (`entries` then loses its
    /// meaning: growing marks the whole image dirty).
    fn take_slot(&mut self, entries: &mut Vec<usize>) -> u32 {
        self.count += 1;
        if let Some(s) = self.free.pop() {
            return s;
        }
        if self.used == self.capacity {
            self.grow();
            entries.clear();
        }
        self.used += 1;
        self.used - 1
    }

    /// Doubles the capacity: leaves move, every node is recomputed, the table is built
    /// again (from the face records written so far), the whole image is dirty.
    fn grow(&mut self) {
        let (old, new) = (self.capacity as usize, self.capacity as usize * 2);
        let mut nodes = vec![0f32; 2 * new];
        nodes[new..new + old].copy_from_slice(&self.nodes[old..2 * old]);
        self.nodes = nodes;
        let mut bounds = vec![tree::EMPTY_BOUNDS; 2 * new];
        bounds[new..new + old].copy_from_slice(&self.bounds[old..2 * old]);
        self.bounds = bounds;
        self.faces.resize(new, [0, 0]);
        self.capacity = new as u32;
        self.rebuild_nodes();
        self.table = lookup::FaceTable::with_len(2 * new);
        for s in 0..self.used {
            if self.faces[s as usize] != [0, 0] {
                self.table.insert(&self.faces, s);
            }
        }
        self.mark_all_dirty();
    }

    fn rebuild_nodes(&mut self) {
        for i in (1..self.capacity as usize).rev() {
            self.set_node(i);
        }
    }

    /// Checks the structure against the world: every light face present once, in its
    /// brick's slots, with its material's weight; every node the sum of its children.
    pub fn validate(&self, view: &impl VoxelSource) -> std::result::Result<(), String> {
        let c = self.capacity as usize;
        for i in 1..c {
            if self.nodes[i] != self.nodes[2 * i] + self.nodes[2 * i + 1] {
                return Err(format!("light node {i} is not the sum of its children"));
            }
            if self.bounds[i] != tree::union(self.bounds[2 * i], self.bounds[2 * i + 1]) {
                return Err(format!(
                    "light node {i}'s bounds are not its children's union"
                ));
            }
        }
        for s in 0..c {
            let record = self.faces[s];
            let expected = if self.nodes[c + s] > 0.0 {
                tree::leaf_bounds(LightFace::unpack(record))
            } else {
                tree::EMPTY_BOUNDS
            };
            if self.bounds[c + s] != expected {
                return Err(format!("slot {s}: leaf bounds are not its face's"));
            }
            if self.nodes[c + s] > 0.0 {
                let (w0, y) = lookup::key(record);
                if self.table.find(&self.faces, w0, y) != Some(s as u32) {
                    return Err(format!("slot {s}: its face does not find it in the table"));
                }
            }
        }
        let entries = self.table.entries.iter().filter(|&&e| e != 0).count();
        if entries != self.count as usize || self.table.entries.len() != 2 * c {
            return Err(format!(
                "the face table holds {entries} of {} entries for {} faces",
                self.table.entries.len(),
                self.count
            ));
        }
        let mut expected: HashMap<u32, Vec<[u32; 2]>> = HashMap::new();
        let mut lit = HashSet::new();
        let dims = view.grid();
        view.visit_bricks(&mut |b| {
            let cell = dims.cell_index(b) as u32;
            let lights = brick_lights(view, &self.weights, b);
            if lights.lit {
                lit.insert(cell);
            }
            if !lights.faces.is_empty() {
                expected.insert(cell, lights.faces);
            }
        });
        let mut count = 0;
        for (cell, faces) in &expected {
            let slots = self.slots.get(cell).ok_or_else(|| {
                format!(
                    "brick {} has light faces and none stored",
                    dims.cell_coord(*cell as usize)
                )
            })?;
            let got: Vec<[u32; 2]> = slots.iter().map(|s| self.faces[*s as usize]).collect();
            if &got != faces {
                return Err(format!(
                    "brick {}: light faces {got:?}, expected {faces:?}",
                    dims.cell_coord(*cell as usize)
                ));
            }
            for s in slots {
                let w = self.weights[self.face(*s).material as usize];
                if self.nodes[c + *s as usize] != w {
                    return Err(format!("slot {s}: leaf is not its material's weight"));
                }
            }
            count += faces.len() as u32;
        }
        if lit != self.lit_cells {
            return Err("the bricks marked as holding lit voxels are not those that do".into());
        }
        if self.slots.len() != expected.len() || count != self.count {
            return Err(format!(
                "{} bricks / {} faces stored, {} / {count} expected",
                self.slots.len(),
                self.count,
                expected.len()
            ));
        }
        Ok(())
    }
}

/// What the light index reads of the world: its grid, each brick's voxels and whether a
/// voxel is solid. The world's view implements it; the index never sees the world itself.
pub trait VoxelSource {
    /// The grid.
    fn grid(&self) -> GridDims;
    /// Calls `f` with every non-empty brick's coordinate.
    fn visit_bricks(&self, f: &mut dyn FnMut(UVec3));
    /// Calls `f` with brick `b`'s occupancy and materials.
    fn read_brick(&self, b: UVec3, f: &mut dyn FnMut(&Mask, BrickMaterials<'_>));
    /// Whether voxel `v` (inside the grid) is solid.
    fn solid(&self, v: IVec3) -> bool;
}

/// The light faces of brick `b` under `weights`, read from the view (the brick's voxels and,
/// for faces on its boundary, the neighbouring bricks').
pub(crate) fn brick_lights(view: &impl VoxelSource, weights: &[f32; 256], b: UVec3) -> BrickLights {
    let dims: GridDims = view.grid();
    let cell = dims.cell_index(b) as u32;
    let morton = tree::morton(b);
    let none = BrickLights {
        cell,
        morton,
        lit: false,
        faces: Vec::new(),
    };
    let lit = |m: u8| weights[m as usize] > 0.0;
    let mut faces = Vec::new();
    let mut any_lit = false;
    view.read_brick(b, &mut |mask, mats| {
        let n = mask.count() as usize;
        any_lit = (0..n).any(|k| lit(mats.at(k)));
        if any_lit {
            faces = lit_faces(view, dims, b, mask, mats, &lit);
        }
    });
    if !any_lit {
        return none;
    }
    BrickLights {
        cell,
        morton,
        lit: true,
        faces,
    }
}

/// The uncovered faces of brick `b`'s lit voxels.
fn lit_faces(
    view: &impl VoxelSource,
    dims: GridDims,
    b: UVec3,
    mask: &Mask,
    mats: BrickMaterials<'_>,
    lit: &impl Fn(u8) -> bool,
) -> Vec<[u32; 2]> {
    let base = (b * 8).as_ivec3();
    let mut faces = Vec::new();
    for (k, bit) in mask.ones().enumerate() {
        let m = mats.at(k);
        if !lit(m) {
            continue;
        }
        let local = IVec3::new((bit & 7) as i32, ((bit >> 3) & 7) as i32, (bit >> 6) as i32);
        let v = base + local;
        for (f, n) in FACE_NORMALS.iter().enumerate() {
            let nb = v + *n;
            if !dims.contains_voxel(nb) {
                continue;
            }
            let l = local + *n;
            let covered = if l.cmpge(IVec3::ZERO).all() && l.cmplt(IVec3::splat(8)).all() {
                mask.get(crate::brick::voxel_bit(l.x, l.y, l.z))
            } else {
                view.solid(nb)
            };
            if !covered {
                faces.push(
                    LightFace {
                        voxel: v,
                        face: f as u8,
                        material: m,
                    }
                    .pack(),
                );
            }
        }
    }
    faces
}

/// The lights of the bricks an edit changed and of their face neighbours that hold lit
/// voxels (their boundary faces may have been covered or uncovered).
pub(crate) fn recompute(
    view: &impl VoxelSource,
    lights: &Lights,
    changed: &[UVec3],
) -> Vec<BrickLights> {
    let dims = view.grid();
    let grid = dims.bricks().as_ivec3();
    let mut cells: Vec<UVec3> = Vec::with_capacity(changed.len());
    let mut seen = HashSet::with_capacity(changed.len() * 2);
    for &b in changed {
        if seen.insert(b) {
            cells.push(b);
        }
        for n in FACE_NORMALS {
            let nb = b.as_ivec3() + n;
            if nb.cmplt(IVec3::ZERO).any() || nb.cmpge(grid).any() {
                continue;
            }
            let nb = nb.as_uvec3();
            if lights.is_lit_cell(dims.cell_index(nb) as u32) && seen.insert(nb) {
                cells.push(nb);
            }
        }
    }
    cells
        .into_iter()
        .map(|b| brick_lights(view, &lights.weights, b))
        .collect()
}

/// Every brick's lights (a full rescan: loading, or a material becoming a light or ceasing
/// to be one).
pub(crate) fn rescan(view: &impl VoxelSource, weights: &[f32; 256]) -> Vec<BrickLights> {
    let mut out = Vec::new();
    view.visit_bricks(&mut |b| {
        let l = brick_lights(view, weights, b);
        if l.lit {
            out.push(l);
        }
    });
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn face_records_round_trip() {
        let f = LightFace {
            voxel: IVec3::new(4095, 1023, 4000),
            face: 5,
            material: 255,
        };
        assert_eq!(LightFace::unpack(f.pack()), f);
    }
}

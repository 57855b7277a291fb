//! The faces of a voxel grid as quads: every face between a solid voxel and an empty one —
//! or a voxel of another material where either is see-through (a dielectric), so glass and
//! water keep their surfaces against what they touch — merged, with `greedy`, into the
//! largest rectangles of one material per plane (row by row, then as many rows down as match).
//!
//! Faces are found a brick at a time (each brick's neighbours looked up once per side), kept
//! per plane as (u, w, material) cells, and each plane is merged on a grid of its faces'
//! bounds only: memory follows the faces, not the volume. The merged quads meet at
//! T-junctions (a long edge beside several short ones): exact in position, but a renderer may
//! show hairline cracks there; the per-face form (`greedy` off) is watertight.

use brickmap::Mask;
use brickmap::brick::voxel_bit;
use glam::IVec3;
use std::collections::HashMap;

/// One rectangle of faces: corners (voxel-corner coordinates) counter-clockwise seen from
/// the side its normal points to, its unit normal, its material.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Quad {
    /// The corners, counter-clockwise from outside.
    pub corners: [IVec3; 4],
    /// The outward unit normal (one axis, ±1).
    pub normal: IVec3,
    /// The material of the voxel the face belongs to.
    pub material: u8,
}

impl Quad {
    /// Its area in voxel faces.
    pub fn area(&self) -> i64 {
        let d = (self.corners[2] - self.corners[0]).abs().as_i64vec3();
        let a = self
            .normal
            .abs()
            .to_array()
            .iter()
            .position(|c| *c == 1)
            .unwrap_or(0);
        d[(a + 1) % 3] * d[(a + 2) % 3]
    }
}

/// Where the voxels come from: bricks of 8³ (solid mask, material per voxel index).
pub trait Bricks {
    /// The coordinates of every non-empty brick.
    fn non_empty(&self) -> Vec<IVec3>;
    /// A brick's voxels (None: empty or outside).
    fn brick(&self, b: IVec3) -> Option<(Mask, Box<[u8; 512]>)>;
}

impl Bricks for brickmap::WorldView<'_> {
    fn non_empty(&self) -> Vec<IVec3> {
        let mut out = Vec::new();
        self.for_each_brick(|b, _, _| out.push(b.as_ivec3()));
        out
    }

    fn brick(&self, b: IVec3) -> Option<(Mask, Box<[u8; 512]>)> {
        let bricks = self.dims().bricks().as_ivec3();
        if b.cmplt(IVec3::ZERO).any() || b.cmpge(bricks).any() {
            return None;
        }
        let (mask, mats) = self.brick_voxels(b.as_uvec3());
        (!mask.is_empty()).then(|| (mask, Box::new(mats)))
    }
}

impl Bricks for brickmap::objects::Model {
    fn non_empty(&self) -> Vec<IVec3> {
        self.bricks().map(|(b, _)| b.as_ivec3()).collect()
    }

    fn brick(&self, b: IVec3) -> Option<(Mask, Box<[u8; 512]>)> {
        if b.cmplt(IVec3::ZERO).any() {
            return None;
        }
        let m = brickmap::objects::Model::brick(self, b.as_uvec3())?;
        let mut mats = Box::new([0u8; 512]);
        for bit in m.mask.ones() {
            mats[bit] = m.material(bit);
        }
        Some((m.mask, mats))
    }
}

/// Whether the face of a voxel of material `a` towards a neighbour (`b`: its material, None
/// where empty) shows.
fn shows(a: u8, b: Option<u8>, see_through: &[bool; 256]) -> bool {
    match b {
        None => true,
        Some(b) => {
            let (ta, tb) = (see_through[a as usize], see_through[b as usize]);
            ta != tb || (ta && a != b)
        }
    }
}

/// A plane of faces: axis, side (+1 / −1) and the coordinate of the plane along the axis.
type Plane = (usize, i32, i32);

/// The quads of every showing face of `src` (`see_through[m]`: material m is a dielectric),
/// merged into rectangles with `greedy`, one quad per face without. Sorted (plane, then
/// position), so the same voxels give the same quads. `watch` hears the part of the bricks
/// done every 1,024 bricks; when it says stop, None comes back.
pub fn quads(
    src: &dyn Bricks,
    see_through: &[bool; 256],
    greedy: bool,
    watch: &dyn Fn(f64) -> bool,
) -> Option<Vec<Quad>> {
    let mut planes: HashMap<Plane, Vec<(i32, i32, u8)>> = HashMap::new();
    let mut bricks = src.non_empty();
    bricks.sort_by_key(|b| (b.x, b.y, b.z));
    let any_clear = see_through.iter().any(|c| *c);
    let has_clear = |mask: &Mask, mats: &[u8; 512]| {
        any_clear && mask.ones().any(|bit| see_through[mats[bit] as usize])
    };
    let count = bricks.len().max(1) as f64;
    for (i, b) in bricks.into_iter().enumerate() {
        if i % 1024 == 1023 && !watch(i as f64 / count) {
            return None;
        }
        let Some((mask, mats)) = src.brick(b) else {
            continue;
        };
        let min = b * 8;
        let clear_here = has_clear(&mask, &mats);
        for k in 0..6 {
            let axis = k / 2;
            let sign = if k % 2 == 0 { -1 } else { 1 };
            let mut d = IVec3::ZERO;
            d[axis] = sign;
            let next = src.brick(b + d);
            let clear_next = next.as_ref().is_some_and(|(m, x)| has_clear(m, x));
            if !clear_here && !clear_next {
                // Opaque both sides: the faces are the solid voxels whose neighbour along d
                // (inside the brick, or the next brick's facing layer) is empty — whole-mask
                // shifts, then only those voxels visited.
                let mut occupied = mask.shifted(-d);
                if let Some((m, _)) = &next {
                    occupied = occupied.or(&m.shifted(d * 7));
                }
                for bit in mask.and_not(&occupied).ones() {
                    add_face(&mut planes, min + local(bit), axis, sign, mats[bit]);
                }
                continue;
            }
            for bit in mask.ones() {
                let l = local(bit);
                let n = l + d;
                let other = if n.cmpge(IVec3::ZERO).all() && n.cmplt(IVec3::splat(8)).all() {
                    let nb = voxel_bit(n.x, n.y, n.z);
                    mask.get(nb).then(|| mats[nb])
                } else {
                    let w = n.rem_euclid(IVec3::splat(8));
                    let nb = voxel_bit(w.x, w.y, w.z);
                    next.as_ref().and_then(|(m, x)| m.get(nb).then(|| x[nb]))
                };
                if shows(mats[bit], other, see_through) {
                    add_face(&mut planes, min + l, axis, sign, mats[bit]);
                }
            }
        }
    }
    let mut keys: Vec<Plane> = planes.keys().copied().collect();
    keys.sort_unstable();
    let mut out = Vec::new();
    for key in keys {
        let faces = &planes[&key];
        if greedy {
            merge(key, faces, &mut out);
        } else {
            let mut faces = faces.clone();
            faces.sort_unstable();
            for (u, w, m) in faces {
                out.push(quad(key, (u, w), (u + 1, w + 1), m));
            }
        }
    }
    Some(out)
}

/// A voxel's position in its brick from its bit.
fn local(bit: usize) -> IVec3 {
    IVec3::new(bit as i32 & 7, (bit as i32 >> 3) & 7, bit as i32 >> 6)
}

/// Keeps the face of voxel `v` on the `sign` side of `axis` with its plane's others.
fn add_face(
    planes: &mut HashMap<Plane, Vec<(i32, i32, u8)>>,
    v: IVec3,
    axis: usize,
    sign: i32,
    m: u8,
) {
    let plane = v[axis] + i32::from(sign > 0);
    let (u, w) = (v[(axis + 1) % 3], v[(axis + 2) % 3]);
    planes
        .entry((axis, sign, plane))
        .or_default()
        .push((u, w, m));
}

/// The quad of the rectangle `[u0, u1) × [w0, w1)` of a plane.
fn quad((axis, sign, plane): Plane, (u0, w0): (i32, i32), (u1, w1): (i32, i32), m: u8) -> Quad {
    let p = |u: i32, w: i32| {
        let mut v = IVec3::ZERO;
        v[axis] = plane;
        v[(axis + 1) % 3] = u;
        v[(axis + 2) % 3] = w;
        v
    };
    let mut normal = IVec3::ZERO;
    normal[axis] = sign;
    // (axis, axis + 1, axis + 2) is right-handed: u then w turns counter-clockwise seen
    // from +axis.
    let corners = if sign > 0 {
        [p(u0, w0), p(u1, w0), p(u1, w1), p(u0, w1)]
    } else {
        [p(u0, w0), p(u0, w1), p(u1, w1), p(u1, w0)]
    };
    Quad {
        corners,
        normal,
        material: m,
    }
}

/// Greedy rectangles of one plane's faces: scanning rows, each unused face starts a
/// rectangle as wide as its run of the same material and as tall as whole rows of it match.
fn merge(key: Plane, faces: &[(i32, i32, u8)], out: &mut Vec<Quad>) {
    let (mut lo, mut hi) = ((i32::MAX, i32::MAX), (i32::MIN, i32::MIN));
    for (u, w, _) in faces {
        lo = (lo.0.min(*u), lo.1.min(*w));
        hi = (hi.0.max(*u), hi.1.max(*w));
    }
    let (nu, nw) = ((hi.0 - lo.0 + 1) as usize, (hi.1 - lo.1 + 1) as usize);
    // 0: no face; m + 1: a face of material m.
    let mut grid = vec![0u16; nu * nw];
    for (u, w, m) in faces {
        grid[(w - lo.1) as usize * nu + (u - lo.0) as usize] = u16::from(*m) + 1;
    }
    for w in 0..nw {
        let mut u = 0;
        while u < nu {
            let c = grid[w * nu + u];
            if c == 0 {
                u += 1;
                continue;
            }
            let mut width = 1;
            while u + width < nu && grid[w * nu + u + width] == c {
                width += 1;
            }
            let mut height = 1;
            while w + height < nw
                && grid[(w + height) * nu + u..][..width]
                    .iter()
                    .all(|x| *x == c)
            {
                height += 1;
            }
            for row in w..w + height {
                grid[row * nu + u..][..width].fill(0);
            }
            let (u0, w0) = (lo.0 + u as i32, lo.1 + w as i32);
            out.push(quad(
                key,
                (u0, w0),
                (u0 + width as i32, w0 + height as i32),
                (c - 1) as u8,
            ));
            u += width;
        }
    }
}

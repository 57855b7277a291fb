//! The 48 axis-aligned rotations and reflections ([`Orientation`]: signed permutation
//! matrices, exact on voxels) and an object's placement ([`Placement`]: an orientation, a
//! translation, and the model's integer pivot).
//!
//! Placement rule (MagicaVoxel's, so `.vox` scenes keep their places): voxel v of a model of
//! size s under (R, t) fills the cell ⌊R·(v + ½ − ⌊s/2⌋) + t⌋. Voxel centres are half-integers
//! and a signed permutation keeps them half-integers, so the map is a bijection between the
//! model's cells and the placed box's cells; it is computed in doubled integers
//! (2·cell + 1 = R·(2v + 1 − 2⌊s/2⌋) + 2t), never in floating point. The pivot ⌊s/2⌋ matters
//! on odd axes that R negates.

use glam::IVec3;

/// One of the 48 signed permutation matrices: row i has its single non-zero entry, ±1, in
/// column `cols[i]`; bit i of `neg` says it is −1.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Orientation {
    cols: [u8; 3],
    neg: u8,
}

impl Default for Orientation {
    fn default() -> Self {
        Self::IDENTITY
    }
}

/// The six permutations of the three columns.
const PERMS: [[u8; 3]; 6] = [
    [0, 1, 2],
    [0, 2, 1],
    [1, 0, 2],
    [1, 2, 0],
    [2, 0, 1],
    [2, 1, 0],
];

/// An axis of the world.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum Axis {
    /// x.
    X,
    /// y (up).
    Y,
    /// z.
    Z,
}

impl Axis {
    fn index(self) -> usize {
        match self {
            Axis::X => 0,
            Axis::Y => 1,
            Axis::Z => 2,
        }
    }
}

impl Orientation {
    /// The identity.
    pub const IDENTITY: Orientation = Orientation {
        cols: [0, 1, 2],
        neg: 0,
    };

    /// All 48, the identity first.
    pub fn all() -> impl Iterator<Item = Orientation> {
        PERMS
            .iter()
            .flat_map(|&cols| (0..8u8).map(move |neg| Orientation { cols, neg }))
    }

    /// The entry of row `row`, column `col` (−1, 0 or 1).
    pub fn entry(&self, row: usize, col: usize) -> i32 {
        if self.cols[row] as usize != col {
            0
        } else if self.neg >> row & 1 == 1 {
            -1
        } else {
            1
        }
    }

    /// The orientation with this matrix, if it is a signed permutation.
    pub fn from_matrix(m: [[i32; 3]; 3]) -> Option<Orientation> {
        Orientation::all().find(|o| o.matrix() == m)
    }

    /// The matrix, rows stored.
    pub fn matrix(&self) -> [[i32; 3]; 3] {
        std::array::from_fn(|r| std::array::from_fn(|c| self.entry(r, c)))
    }

    /// The determinant: 1 for a rotation, −1 for a reflection.
    pub fn det(&self) -> i32 {
        let m = self.matrix();
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    }

    /// True for the 24 with determinant −1 (a mirror image).
    pub fn is_reflection(&self) -> bool {
        self.det() < 0
    }

    /// R·v.
    pub fn apply(&self, v: IVec3) -> IVec3 {
        let a = v.to_array();
        let r = |i: usize| {
            let x = a[self.cols[i] as usize];
            if self.neg >> i & 1 == 1 { -x } else { x }
        };
        IVec3::new(r(0), r(1), r(2))
    }

    /// The product self · other: `other` first, then `self`.
    pub fn after(&self, other: &Orientation) -> Orientation {
        // (A·B·v)_i = s_i (B·v)_{a_i} = s_i t_{a_i} v_{b_{a_i}}.
        let cols = self.cols.map(|a| other.cols[a as usize]);
        let neg = (0..3).fold(0u8, |neg, i| {
            neg | ((self.neg >> i ^ other.neg >> self.cols[i]) & 1) << i
        });
        Orientation { cols, neg }
    }

    /// The inverse (the transpose).
    pub fn inverse(&self) -> Orientation {
        let mut cols = [0u8; 3];
        let mut neg = 0u8;
        for i in 0..3 {
            let c = self.cols[i] as usize;
            cols[c] = i as u8;
            neg |= (self.neg >> i & 1) << c;
        }
        Orientation { cols, neg }
    }

    /// A quarter turn about an axis, counter-clockwise looking down the axis towards the
    /// origin (right-handed), `turns` times (any integer; 4 is the identity).
    pub fn quarter_turn(axis: Axis, turns: i32) -> Orientation {
        // +90° about x: (x, y, z) → (x, −z, y); about y: (z, y, −x); about z: (−y, x, z).
        let one = match axis {
            Axis::X => Orientation {
                cols: [0, 2, 1],
                neg: 0b010,
            },
            Axis::Y => Orientation {
                cols: [2, 1, 0],
                neg: 0b100,
            },
            Axis::Z => Orientation {
                cols: [1, 0, 2],
                neg: 0b001,
            },
        };
        let mut r = Orientation::IDENTITY;
        for _ in 0..turns.rem_euclid(4) {
            r = one.after(&r);
        }
        r
    }

    /// The mirror that negates one axis.
    pub fn flip(axis: Axis) -> Orientation {
        Orientation {
            cols: [0, 1, 2],
            neg: 1 << axis.index(),
        }
    }

    /// MagicaVoxel's packed rotation byte (bits 0–1: row 0's column, bits 2–3: row 1's,
    /// bits 4–6: the rows' signs), in the file's own axes. `None` for the 80 bytes below 128
    /// that name no signed permutation.
    pub fn from_vox_byte(byte: u8) -> Option<Orientation> {
        let (c0, c1) = (byte & 3, byte >> 2 & 3);
        if byte >= 128 || c0 == 3 || c1 == 3 || c0 == c1 {
            return None;
        }
        Some(Orientation {
            cols: [c0, c1, 3 - c0 - c1],
            neg: byte >> 4 & 7,
        })
    }

    /// The byte [`Orientation::from_vox_byte`] reads.
    pub fn to_vox_byte(&self) -> u8 {
        self.cols[0] | self.cols[1] << 2 | self.neg << 4
    }

    /// The same map written in other axes: C·R·C⁻¹, for a change of axes C (for example
    /// MagicaVoxel's z-up axes to voxbrick's y-up ones).
    pub fn conjugate(&self, axes: &Orientation) -> Orientation {
        axes.after(self).after(&axes.inverse())
    }
}

/// Where an object's model lands: orientation R and translation t about the model's pivot
/// ⌊s/2⌋ (the rule in the module doc). Groups carry one too; a child's placement in the world
/// is its parent's composed with its own ([`Placement::then`]).
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize,
)]
pub struct Placement {
    /// The orientation.
    #[serde(with = "vox_byte")]
    pub rot: Orientation,
    /// The translation, in voxels.
    pub t: IVec3,
}

impl Placement {
    /// No rotation, no translation.
    pub const IDENTITY: Placement = Placement {
        rot: Orientation::IDENTITY,
        t: IVec3::ZERO,
    };

    /// A translation only.
    pub fn at(t: IVec3) -> Placement {
        Placement {
            rot: Orientation::IDENTITY,
            t,
        }
    }

    /// `local` inside `self`: p ↦ self(local(p)).
    pub fn then(&self, local: &Placement) -> Placement {
        Placement {
            rot: self.rot.after(&local.rot),
            t: self.rot.apply(local.t) + self.t,
        }
    }

    /// The cell model voxel `v` of a model of `size` lands in.
    pub fn place(&self, v: IVec3, size: IVec3) -> IVec3 {
        let twice = self.rot.apply(v * 2 + 1 - (size / 2) * 2) + self.t * 2;
        // Odd in every component, so the halving is exact.
        (twice - 1) / 2
    }

    /// The model voxel that lands in world cell `w` (the exact inverse of
    /// [`Placement::place`]; it may lie outside the model).
    pub fn unplace(&self, w: IVec3, size: IVec3) -> IVec3 {
        let twice = self.rot.inverse().apply(w * 2 + 1 - self.t * 2) + (size / 2) * 2;
        (twice - 1) / 2
    }

    /// The placed box of a model of `size`: its lowest cell and one past its highest.
    pub fn bounds(&self, size: IVec3) -> (IVec3, IVec3) {
        let a = self.place(IVec3::ZERO, size);
        let b = self.place(size - 1, size);
        (a.min(b), a.max(b) + 1)
    }
}

/// Placements are saved with their orientation as MagicaVoxel's byte (one readable number).
mod vox_byte {
    use super::Orientation;
    use serde::{Deserialize, Deserializer, Serializer, de::Error};

    pub fn serialize<S: Serializer>(o: &Orientation, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_u8(o.to_vox_byte())
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Orientation, D::Error> {
        let b = u8::deserialize(d)?;
        Orientation::from_vox_byte(b)
            .ok_or_else(|| D::Error::custom(format!("{b} is not a rotation byte")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mul(a: [[i32; 3]; 3], b: [[i32; 3]; 3]) -> [[i32; 3]; 3] {
        std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
    }

    #[test]
    fn the_48_are_distinct_closed_and_each_has_its_inverse() {
        let all: Vec<_> = Orientation::all().collect();
        assert_eq!(all.len(), 48);
        assert_eq!(all[0], Orientation::IDENTITY);
        let set: std::collections::HashSet<_> = all.iter().map(|o| o.matrix()).collect();
        assert_eq!(set.len(), 48);
        assert_eq!(all.iter().filter(|o| o.is_reflection()).count(), 24);
        let v = IVec3::new(3, -5, 7);
        assert_eq!(
            Orientation::from_matrix([[0, 1, 0], [1, 0, 0], [0, 0, 2]]),
            None
        );
        for a in &all {
            assert_eq!(Orientation::from_matrix(a.matrix()), Some(*a));
            assert_eq!(a.after(&a.inverse()), Orientation::IDENTITY, "{a:?}");
            assert_eq!(a.inverse().apply(a.apply(v)), v);
            for b in &all {
                let ab = a.after(b);
                assert_eq!(ab.matrix(), mul(a.matrix(), b.matrix()), "{a:?} {b:?}");
                assert_eq!(ab.apply(v), a.apply(b.apply(v)));
                assert_eq!(ab.det(), a.det() * b.det());
            }
        }
    }

    #[test]
    fn quarter_turns_and_flips() {
        for axis in [Axis::X, Axis::Y, Axis::Z] {
            let q = Orientation::quarter_turn(axis, 1);
            assert!(!q.is_reflection());
            assert_ne!(q, Orientation::IDENTITY);
            assert_eq!(Orientation::quarter_turn(axis, 4), Orientation::IDENTITY);
            assert_eq!(Orientation::quarter_turn(axis, -1), q.inverse());
            assert_eq!(Orientation::quarter_turn(axis, 2), q.after(&q));
            let f = Orientation::flip(axis);
            assert!(f.is_reflection());
            assert_eq!(f.after(&f), Orientation::IDENTITY);
            // The axis itself stays.
            let unit = [IVec3::X, IVec3::Y, IVec3::Z][axis.index()];
            assert_eq!(q.apply(unit), unit);
            assert_eq!(f.apply(unit), -unit);
        }
        // Right-handed: +90° about y takes +x to −z, about z takes +x to +y, about x +y to +z.
        assert_eq!(
            Orientation::quarter_turn(Axis::Y, 1).apply(IVec3::X),
            -IVec3::Z
        );
        assert_eq!(
            Orientation::quarter_turn(Axis::Z, 1).apply(IVec3::X),
            IVec3::Y
        );
        assert_eq!(
            Orientation::quarter_turn(Axis::X, 1).apply(IVec3::Y),
            IVec3::Z
        );
    }

    #[test]
    fn vox_bytes_round_trip_and_name_exactly_the_48() {
        let mut valid = 0;
        for b in 0..=255u8 {
            if let Some(o) = Orientation::from_vox_byte(b) {
                valid += 1;
                assert_eq!(o.to_vox_byte(), b);
            }
        }
        assert_eq!(valid, 48);
        assert_eq!(
            Orientation::from_vox_byte(0b0000100),
            Some(Orientation::IDENTITY)
        );
        for o in Orientation::all() {
            assert_eq!(Orientation::from_vox_byte(o.to_vox_byte()), Some(o));
        }
    }

    #[test]
    fn placement_is_a_bijection_onto_its_box_for_every_orientation() {
        for size in [IVec3::new(3, 4, 5), IVec3::new(1, 2, 7)] {
            for rot in Orientation::all() {
                let p = Placement {
                    rot,
                    t: IVec3::new(10, -3, 4),
                };
                let (lo, hi) = p.bounds(size);
                assert_eq!(
                    (hi - lo).abs().to_array().iter().product::<i32>(),
                    size.element_product()
                );
                let mut seen = std::collections::HashSet::new();
                for x in 0..size.x {
                    for y in 0..size.y {
                        for z in 0..size.z {
                            let v = IVec3::new(x, y, z);
                            let w = p.place(v, size);
                            assert!(w.cmpge(lo).all() && w.cmplt(hi).all(), "{rot:?} {v} → {w}");
                            assert!(seen.insert(w));
                            assert_eq!(p.unplace(w, size), v);
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn placement_matches_the_floor_rule_and_composes() {
        let size = IVec3::new(5, 2, 3);
        let all: Vec<_> = Orientation::all().collect();
        for (i, rot) in all.iter().enumerate() {
            let p = Placement {
                rot: *rot,
                t: IVec3::new(-2, 7, 1),
            };
            let v = IVec3::new(4, 1, 0);
            // ⌊R·(v + ½ − ⌊s/2⌋) + t⌋ in floating point, for comparison.
            let c = (v.as_dvec3() + 0.5 - (size / 2).as_dvec3()).to_array();
            let m = rot.matrix();
            let r: [f64; 3] =
                std::array::from_fn(|k| (0..3).map(|j| m[k][j] as f64 * c[j]).sum::<f64>());
            let want = (glam::DVec3::from_array(r) + p.t.as_dvec3())
                .floor()
                .as_ivec3();
            assert_eq!(p.place(v, size), want, "{rot:?}");
            // A group's placement composed with a child's.
            let outer = Placement {
                rot: all[(i * 7 + 3) % 48],
                t: IVec3::new(5, 0, -9),
            };
            let both = outer.then(&p);
            let q = IVec3::new(3, -1, 2);
            assert_eq!(
                both.rot.apply(q) + both.t,
                outer.rot.apply(p.rot.apply(q) + p.t) + outer.t
            );
        }
    }

    #[test]
    fn placements_save_their_orientation_as_the_vox_byte() {
        let p = Placement {
            rot: Orientation::quarter_turn(Axis::Y, 1),
            t: IVec3::new(1, 2, 3),
        };
        let text = ron::to_string(&p).unwrap();
        assert!(
            text.contains(&format!("rot:{}", p.rot.to_vox_byte())),
            "{text}"
        );
        assert_eq!(ron::from_str::<Placement>(&text).unwrap(), p);
        assert!(ron::from_str::<Placement>("(rot:3,t:(0,0,0))").is_err());
    }
}

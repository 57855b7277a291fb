//! A new scene's material table built from what an imported file says each voxel is: a
//! material kind, its parameter value (roughness, index of refraction, strength) and an sRGB
//! colour. The same triple is one material; a colour is one entry of the colour table; the
//! first material replaces the new world's default one. Files with true colour (Qubicle)
//! reduce their colours first ([`reduce_colours`]): the 256 most used kept exactly, every
//! other mapped to its nearest kept one.

use brickmap::{Material, MaterialKind, World};
use std::collections::HashMap;

/// Builds materials into a fresh world's table.
pub struct TableBuilder<'w> {
    world: &'w World,
    colours: HashMap<[u8; 3], u8>,
    materials: HashMap<(MaterialKind, u32, [u8; 3]), u8>,
    params: HashMap<(MaterialKind, u32), u8>,
    next_param: HashMap<MaterialKind, u8>,
}

impl<'w> TableBuilder<'w> {
    /// A builder for `world`, which must hold no voxels yet.
    pub fn new(world: &'w World) -> Self {
        Self {
            world,
            colours: HashMap::new(),
            materials: HashMap::new(),
            params: HashMap::new(),
            next_param: HashMap::new(),
        }
    }

    /// The material index of `kind` with parameter `value` (ignored for lambertian; metal:
    /// roughness 0..1, dielectric: index of refraction, emissive: strength) and `rgb`.
    pub fn material(&mut self, kind: MaterialKind, value: f32, rgb: [u8; 3]) -> Result<u8, String> {
        let value = if kind == MaterialKind::Lambertian {
            0.0
        } else {
            value
        };
        let key = (kind, value.to_bits(), rgb);
        if let Some(&m) = self.materials.get(&key) {
            return Ok(m);
        }
        let colour = match self.colours.get(&rgb) {
            Some(&c) => c,
            None => {
                let c = u8::try_from(self.colours.len())
                    .map_err(|_| "more than 256 colours".to_string())?;
                self.world.set_colour(c, rgb);
                self.colours.insert(rgb, c);
                c
            }
        };
        let param = self.param(kind, value)?;
        let m = Material {
            kind,
            param,
            colour,
        };
        let index = if self.materials.is_empty() {
            self.world.set_material(0, m).map_err(|e| e.to_string())?;
            0
        } else {
            self.world.push_material(m).map_err(|e| e.to_string())?
        };
        self.materials.insert(key, index);
        Ok(index)
    }

    /// The parameter slot of `value` for `kind` (metal: roughness i / 63).
    fn param(&mut self, kind: MaterialKind, value: f32) -> Result<u8, String> {
        match kind {
            MaterialKind::Lambertian => return Ok(0),
            MaterialKind::Metal => return Ok((value.clamp(0.0, 1.0) * 63.0).round() as u8),
            _ => {}
        }
        if let Some(&p) = self.params.get(&(kind, value.to_bits())) {
            return Ok(p);
        }
        let next = self.next_param.entry(kind).or_insert(2);
        if *next as usize >= brickmap::material::PARAMS {
            return Err(format!(
                "more than {} {kind:?} parameters",
                brickmap::material::PARAMS - 2
            ));
        }
        let p = *next;
        *next += 1;
        self.world
            .set_param(kind, p, value)
            .map_err(|e| e.to_string())?;
        self.params.insert((kind, value.to_bits()), p);
        Ok(p)
    }
}

/// `counts` of colours reduced to at most `max`: a map from every colour to the colour it
/// becomes (the `max` most used map to themselves; each other to its nearest of those by
/// squared RGB distance, ties to the more used), and how many colours were merged.
pub fn reduce_colours(
    counts: &HashMap<[u8; 3], u64>,
    max: usize,
) -> (HashMap<[u8; 3], [u8; 3]>, usize) {
    let mut by_use: Vec<([u8; 3], u64)> = counts.iter().map(|(c, n)| (*c, *n)).collect();
    // Most used first; equal counts by colour, so the choice does not depend on hashing.
    by_use.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    let kept: Vec<[u8; 3]> = by_use.iter().take(max).map(|(c, _)| *c).collect();
    let distance = |a: [u8; 3], b: [u8; 3]| -> i32 {
        (0..3).map(|i| (a[i] as i32 - b[i] as i32).pow(2)).sum()
    };
    let map = by_use
        .iter()
        .map(|(c, _)| {
            let to = if kept.contains(c) {
                *c
            } else {
                *kept
                    .iter()
                    .min_by_key(|k| distance(**k, *c))
                    .expect("a colour is kept")
            };
            (*c, to)
        })
        .collect();
    (map, by_use.len().saturating_sub(max))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_most_used_colours_stay_and_the_rest_go_to_their_nearest() {
        let mut counts = HashMap::new();
        counts.insert([0, 0, 0], 10);
        counts.insert([255, 255, 255], 9);
        counts.insert([250, 250, 250], 1);
        counts.insert([3, 3, 3], 2);
        let (map, merged) = reduce_colours(&counts, 2);
        assert_eq!(merged, 2);
        assert_eq!(map[&[0, 0, 0]], [0, 0, 0]);
        assert_eq!(map[&[250, 250, 250]], [255, 255, 255]);
        assert_eq!(map[&[3, 3, 3]], [0, 0, 0]);
        let (same, none) = reduce_colours(&counts, 256);
        assert_eq!(none, 0);
        assert!(same.iter().all(|(a, b)| a == b));
    }
}

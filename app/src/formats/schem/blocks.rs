//! The block table of Sponge schematics: Minecraft block ids to voxbrick materials and back
//! (`assets/schem/blocks.ron`, or an edited copy), with the rule that derives a block the
//! table does not list from one it does (`birch_stairs` → `birch_planks`; the table's header
//! says the rule).

use super::FormatError;
use brickmap::MaterialKind;
use std::collections::{HashMap, HashSet};
use std::path::Path;

/// The block table shipped with voxbrick.
pub const BUILTIN_BLOCKS: &str = include_str!("../../../../assets/schem/blocks.ron");

#[derive(Clone, Copy, Debug, PartialEq, serde::Deserialize)]
enum Kind {
    Lambertian,
    Metal,
    Dielectric,
    Emissive,
}

/// A block's material in the table.
#[derive(Clone, Copy, Debug, PartialEq, serde::Deserialize)]
pub(super) struct Spec {
    kind: Kind,
    #[serde(default)]
    pub(super) value: f32,
    colour: (u8, u8, u8),
}

impl Spec {
    pub(super) fn kind(&self) -> MaterialKind {
        match self.kind {
            Kind::Lambertian => MaterialKind::Lambertian,
            Kind::Metal => MaterialKind::Metal,
            Kind::Dielectric => MaterialKind::Dielectric,
            Kind::Emissive => MaterialKind::Emissive,
        }
    }
    pub(super) fn rgb(&self) -> [u8; 3] {
        [self.colour.0, self.colour.1, self.colour.2]
    }
}

#[derive(serde::Deserialize)]
struct TableFile {
    empty: Vec<String>,
    unknown: Spec,
    blocks: Vec<(String, Spec)>,
}

/// How a block was found in the table.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) enum Found {
    /// Listed (or empty).
    Listed,
    /// Derived from this listed block.
    Derived(String),
    /// Neither: the unknown material.
    Unknown,
}

/// Prefixes dropped to find a block's base (`stripped_oak_log` → `oak_log`).
const PREFIXES: [&str; 10] = [
    "waxed_",
    "stripped_",
    "potted_",
    "infested_",
    "chiseled_",
    "cut_",
    "polished_",
    "smooth_",
    "cracked_",
    "mossy_",
];
/// Shape suffixes dropped to find a block's base (`birch_stairs` → `birch`).
const SUFFIXES: [&str; 29] = [
    "_stairs",
    "_slab",
    "_wall",
    "_fence_gate",
    "_fence",
    "_door",
    "_trapdoor",
    "_button",
    "_pressure_plate",
    "_wall_sign",
    "_hanging_sign",
    "_sign",
    "_pane",
    "_carpet",
    "_bed",
    "_wall_banner",
    "_banner",
    "_concrete_powder",
    "_glazed_terracotta",
    "_wood",
    "_hyphae",
    "_brick",
    "_bricks",
    "_tiles",
    "_pillar",
    "_plant",
    "_wall_head",
    "_wall_fan",
    "_fan",
];
/// What is tried after a base: itself and these endings (`birch` → `birch_planks`).
const ENDINGS: [&str; 11] = [
    "",
    "_planks",
    "s",
    "_bricks",
    "_block",
    "_wool",
    "_concrete",
    "_terracotta",
    "_log",
    "_stem",
    "_stained_glass",
];

/// The names a block not listed is tried as, in order (the table's header says the rule).
fn derivations(id: &str) -> Vec<String> {
    let (ns, name) = id.split_once(':').unwrap_or(("minecraft", id));
    let mut bases = vec![name.to_string()];
    let mut k = 0;
    while k < bases.len() && bases.len() < 16 {
        let b = bases[k].clone();
        for p in PREFIXES {
            if let Some(rest) = b.strip_prefix(p).filter(|r| !r.is_empty()) {
                bases.push(rest.to_string());
            }
        }
        k += 1;
    }
    let mut out = vec![name.to_string()];
    for b in &bases {
        out.extend(ENDINGS.iter().map(|e| format!("{b}{e}")));
        for s in SUFFIXES {
            if let Some(stem) = b.strip_suffix(s).filter(|r| !r.is_empty()) {
                out.extend(ENDINGS.iter().map(|e| format!("{stem}{e}")));
            }
        }
    }
    if name.ends_with("_ore") {
        out.push(
            if name.starts_with("deepslate_") {
                "deepslate"
            } else if name.starts_with("nether_") {
                "netherrack"
            } else {
                "stone"
            }
            .to_string(),
        );
    }
    if name.starts_with("dead_") && name.contains("coral") {
        out.push("dead_coral_block".to_string());
    }
    out.into_iter()
        .skip(1)
        .map(|n| format!("{ns}:{n}"))
        .collect()
}

/// Block ids to materials and back.
#[derive(Clone, Debug)]
pub struct BlockTable {
    empty: HashSet<String>,
    unknown: Spec,
    blocks: Vec<(String, Spec)>,
    index: HashMap<String, usize>,
}

impl BlockTable {
    /// The table shipped in `assets/schem/blocks.ron`.
    pub fn builtin() -> Self {
        Self::parse(BUILTIN_BLOCKS).expect("the shipped block table parses")
    }

    /// A table from its RON text.
    pub fn parse(text: &str) -> Result<Self, String> {
        let f: TableFile = ron::from_str(text).map_err(|e| format!("not a block table: {e}"))?;
        if f.blocks.is_empty() {
            return Err("a block table lists at least one block".into());
        }
        for (name, s) in &f.blocks {
            let ok = match s.kind {
                Kind::Lambertian => true,
                Kind::Metal => (0.0..=1.0).contains(&s.value),
                Kind::Dielectric => (1.0..=4.0).contains(&s.value),
                Kind::Emissive => s.value.is_finite() && s.value > 0.0 && s.value <= 1e6,
            };
            if !ok {
                return Err(format!(
                    "{name}: {:?} with value {} is out of range",
                    s.kind, s.value
                ));
            }
        }
        let mut index = HashMap::new();
        for (k, (name, _)) in f.blocks.iter().enumerate() {
            index.entry(name.clone()).or_insert(k);
        }
        Ok(Self {
            empty: f.empty.into_iter().collect(),
            unknown: f.unknown,
            blocks: f.blocks,
            index,
        })
    }

    /// A table from a RON file.
    pub fn load(path: &Path) -> Result<Self, FormatError> {
        let text = std::fs::read_to_string(path).map_err(|e| FormatError::io(path, e))?;
        Self::parse(&text).map_err(|m| FormatError::invalid(path, m))
    }

    /// The material of a block state (None: empty) and how it was found.
    pub(super) fn spec(&self, state: &str) -> (Option<Spec>, Found) {
        let id = state.split('[').next().unwrap_or(state).trim();
        let id = if id.contains(':') {
            id.to_string()
        } else {
            format!("minecraft:{id}")
        };
        if self.empty.contains(&id) {
            return (None, Found::Listed);
        }
        if let Some(&k) = self.index.get(&id) {
            return (Some(self.blocks[k].1), Found::Listed);
        }
        for c in derivations(&id) {
            if self.empty.contains(&c) {
                return (None, Found::Derived(c));
            }
            if let Some(&k) = self.index.get(&c) {
                return (Some(self.blocks[k].1), Found::Derived(c));
            }
        }
        (Some(self.unknown), Found::Unknown)
    }

    /// The block a material is written as: the first listed with the same material, else
    /// the nearest in colour of its kind, else of any kind; and whether it was exact.
    pub(super) fn block_of(&self, kind: MaterialKind, value: f32, rgb: [u8; 3]) -> (&str, bool) {
        let same = |s: &Spec| {
            s.kind() == kind
                && s.rgb() == rgb
                && (kind == MaterialKind::Lambertian || (s.value - value).abs() < 1e-3)
        };
        if let Some((name, _)) = self.blocks.iter().find(|(_, s)| same(s)) {
            return (name, true);
        }
        let distance = |s: &Spec| -> i32 {
            let c = s.rgb();
            (0..3).map(|i| (c[i] as i32 - rgb[i] as i32).pow(2)).sum()
        };
        let nearest = self
            .blocks
            .iter()
            .filter(|(_, s)| s.kind() == kind)
            .min_by_key(|(_, s)| distance(s))
            .or_else(|| self.blocks.iter().min_by_key(|(_, s)| distance(s)))
            .expect("a table lists a block");
        (&nearest.0, false)
    }
}

//! Why a `.vox` file could not be imported or a scene exported: one variant per cause, so a
//! caller tells them apart by kind (the import explains a missing model by the chunks it could
//! not read; the editor says what to change), and each message says what is wrong.

use super::{MAX_DEPTH, MAX_PLACED_VOXELS};
use brickmap::MaterialKind;
use glam::IVec3;

/// A `.vox` import or export failure.
#[derive(Debug, thiserror::Error)]
pub enum VoxError {
    /// A Ken Silverman SLAB6 file (a plain volume, no "VOX " header).
    #[error(
        "this is a Ken Silverman SLAB6 .vox (a plain {0}×{1}×{2} volume with a 768-byte palette, no \"VOX \" header), which voxbrick does not import; MagicaVoxel or vengi can convert it"
    )]
    Slab6(u64, u64, u64),
    /// The chunk structure, or what the parser found in it, is broken.
    #[error("not a valid .vox file: {0}")]
    Malformed(String),
    /// The scene graph nests deeper than [`MAX_DEPTH`] (or is cyclic).
    #[error("scene graph deeper than {MAX_DEPTH} levels (or cyclic)")]
    TooDeep,
    /// A node refers to a node that does not exist.
    #[error("scene graph refers to missing node {0}")]
    MissingNode(u32),
    /// A transform node's translation is not three integers within ±2^20.
    #[error("node {node}: translation {value:?} is not three integers within ±2^20")]
    BadTranslation {
        /// The node.
        node: u32,
        /// Its `_t` attribute.
        value: String,
    },
    /// A shape refers to a model that is not in the SIZE/XYZI chunks; `unread` names the
    /// file's chunks voxbrick does not read (where its voxels may be).
    #[error("shape refers to missing model {model}{}", unread_note(unread))]
    MissingModel {
        /// The model id.
        model: u32,
        /// Chunks in the file that voxbrick does not read.
        unread: Vec<String>,
    },
    /// The scene places more than [`MAX_PLACED_VOXELS`] voxels.
    #[error("the scene places more than {MAX_PLACED_VOXELS} voxels")]
    TooManyVoxels,
    /// The file holds voxels but every one was left out.
    #[error(
        "nothing to import: the file's {models} models hold {voxels} voxels, and every one was left out ({why})"
    )]
    NothingPlaced {
        /// Models in the file.
        models: usize,
        /// Voxels they hold.
        voxels: u64,
        /// What left them out.
        why: String,
    },
    /// Every voxel lands outside the grid it is imported into.
    #[error(
        "nothing to import: all {voxels} voxels land outside the {grid} voxel grid (try another offset)"
    )]
    OutsideGrid {
        /// Voxels placed.
        voxels: usize,
        /// The grid's size in voxels.
        grid: IVec3,
    },
    /// The offset moves voxels below the grid origin.
    #[error("the offset {0} moves voxels below the grid origin")]
    BelowOrigin(IVec3),
    /// The model needs a grid larger than the largest supported.
    #[error("the model needs a {0} voxel grid, beyond the largest supported")]
    TooLarge(IVec3),
    /// Importing into a scene: no colour slot is free for a new colour.
    #[error("no free colour slot: every colour is used by a material")]
    NoFreeColour,
    /// More distinct parameters of one material kind than its table holds.
    #[error("more than {max} distinct {kind:?} parameters")]
    TooManyParameters {
        /// The kind.
        kind: MaterialKind,
        /// How many one import can add.
        max: usize,
    },
    /// Export: .vox holds at most 255 materials.
    #[error("the scene uses more than 255 materials; .vox holds at most 255")]
    TooManyMaterials,
    /// The world refused (material table, grid, budget).
    #[error(transparent)]
    World(#[from] brickmap::BrickmapError),
}

fn unread_note(unread: &[String]) -> String {
    if unread.is_empty() {
        String::new()
    } else {
        format!(
            ": its voxels are not in SIZE/XYZI chunks; the file also holds {}, which voxbrick does not read",
            unread.join(", ")
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_model_names_the_chunks_voxbrick_does_not_read() {
        let plain = VoxError::MissingModel {
            model: 3,
            unread: vec![],
        };
        assert_eq!(plain.to_string(), "shape refers to missing model 3");
        let teardown = VoxError::MissingModel {
            model: 0,
            unread: vec!["TDCZ (Teardown's compressed voxel data)".into()],
        };
        assert!(
            teardown
                .to_string()
                .ends_with("the file also holds TDCZ (Teardown's compressed voxel data), which voxbrick does not read"),
            "{teardown}"
        );
    }
}

//! Scene file formats: RON projects (`project`, with the voxel payload in `payload`),
//! MagicaVoxel `.vox` (`vox`, its chunk structure checked first by `vox::check`), Qubicle
//! `.qb` (`qb`) and Sponge `.schem` (`schem`, with its block table); meshes, pictures,
//! palettes and heightmaps out or in (`mesh`, `picture`, `palette`, `heightmap`).

pub mod heightmap;
pub mod mesh;
pub mod palette;
pub mod payload;
pub mod picture;
pub mod project;
pub mod qb;
pub mod schem;
pub mod table;
pub mod vox;

use crate::scene::Scene;
use std::path::Path;

/// A PNG's first frame with `transformations`, after `check` accepted its width and height
/// (before the pixels are read); the error says what is wrong.
pub(crate) fn decode_png(
    bytes: &[u8],
    transformations: png::Transformations,
    check: impl Fn(u32, u32) -> Result<(), String>,
) -> Result<(png::OutputInfo, Vec<u8>), String> {
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    decoder.set_transformations(transformations);
    let mut reader = decoder.read_info().map_err(|e| format!("not a PNG: {e}"))?;
    check(reader.info().width, reader.info().height)?;
    let mut buf = vec![
        0;
        reader
            .output_buffer_size()
            .ok_or("the image is too large")?
    ];
    let info = reader
        .next_frame(&mut buf)
        .map_err(|e| format!("reading the image: {e}"))?;
    Ok((info, buf))
}

/// Loads a `.ron` project (version 2 as written, version 1 as one object) or imports a
/// `.vox` file with its groups, objects, layers and shared models (it gets the default sun
/// and sky), choosing by the extension.
pub fn load(path: &Path, workers: usize) -> Result<Scene, FormatError> {
    match Format::of(path)? {
        Format::Project => project::load(path, workers),
        Format::Vox => {
            let bytes = std::fs::read(path).map_err(|e| FormatError::io(path, e))?;
            Ok(vox::import_objects(&bytes, path, workers)?.scene)
        }
        Format::Qb => {
            let bytes = std::fs::read(path).map_err(|e| FormatError::io(path, e))?;
            Ok(qb::import(&bytes, path, workers)?.0)
        }
        Format::Schem => {
            let bytes = std::fs::read(path).map_err(|e| FormatError::io(path, e))?;
            let table = schem::BlockTable::builtin();
            Ok(schem::import(&bytes, path, &table, workers)?.0)
        }
    }
}

/// Saves as a `.ron` project or exports `.vox` (the objects either way), atomically,
/// choosing by the extension.
pub fn save(scene: &Scene, path: &Path) -> Result<(), FormatError> {
    match Format::of(path)? {
        Format::Project => project::save(scene, path),
        Format::Vox => vox::export_file(scene, path).map(|_| ()),
        Format::Qb => qb::export(scene, path).map(|_| ()),
        Format::Schem => schem::export(scene, path, &schem::BlockTable::builtin()).map(|_| ()),
    }
}

/// Why a file could not be read or written. Messages name the file and what is wrong.
#[derive(Debug, thiserror::Error)]
pub enum FormatError {
    /// The file system refused.
    #[error("{path}: {error}")]
    Io {
        /// The file.
        path: String,
        /// The cause (shown in the message, so not chained again).
        error: std::io::Error,
    },
    /// The user stopped it (nothing was written).
    #[error("{path}: cancelled, nothing written")]
    Cancelled {
        /// The file.
        path: String,
    },
    /// The content is not a valid file of this format.
    #[error("{path}: {message}")]
    Invalid {
        /// The file.
        path: String,
        /// What is wrong.
        message: String,
    },
    /// Valid, but from a newer program.
    #[error(
        "{path}: format version {found} is newer than this program understands ({known}); update voxbrick"
    )]
    NewerVersion {
        /// The file.
        path: String,
        /// Its version.
        found: u32,
        /// The newest version known here.
        known: u32,
    },
    /// A `.vox` file could not be imported, or a scene not exported as one.
    #[error("{path}: {error}")]
    Vox {
        /// The file.
        path: String,
        /// The cause (shown in the message, so not chained again).
        error: vox::VoxError,
    },
    /// A project's voxel payload is corrupt.
    #[error("{path}: {error}")]
    Payload {
        /// The file.
        path: String,
        /// What is wrong and where.
        error: payload::PayloadError,
    },
    /// The content does not fit the world (grid, materials, budget).
    #[error("{path}: {error}")]
    World {
        /// The file.
        path: String,
        /// The cause (shown in the message, so not chained again).
        error: brickmap::BrickmapError,
    },
}

impl FormatError {
    pub(crate) fn invalid(path: &Path, message: impl Into<String>) -> Self {
        FormatError::Invalid {
            path: path.display().to_string(),
            message: message.into(),
        }
    }
    pub(crate) fn io(path: &Path, source: std::io::Error) -> Self {
        FormatError::Io {
            path: path.display().to_string(),
            error: source,
        }
    }
    pub(crate) fn vox(path: &Path, error: vox::VoxError) -> Self {
        FormatError::Vox {
            path: path.display().to_string(),
            error,
        }
    }
    pub(crate) fn payload(path: &Path, error: payload::PayloadError) -> Self {
        FormatError::Payload {
            path: path.display().to_string(),
            error,
        }
    }
    pub(crate) fn world(path: &Path, source: brickmap::BrickmapError) -> Self {
        FormatError::World {
            path: path.display().to_string(),
            error: source,
        }
    }
}

/// The formats, by file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// voxbrick project (`.ron`).
    Project,
    /// MagicaVoxel (`.vox`).
    Vox,
    /// Qubicle binary (`.qb`).
    Qb,
    /// Sponge schematic (`.schem`).
    Schem,
}

impl Format {
    /// The format a path's extension names.
    pub fn of(path: &Path) -> Result<Format, FormatError> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase())
            .as_deref()
        {
            Some("ron") => Ok(Format::Project),
            Some("vox") => Ok(Format::Vox),
            Some("qb") => Ok(Format::Qb),
            Some("schem") => Ok(Format::Schem),
            _ => Err(FormatError::invalid(
                path,
                "unknown file type: expected .ron, .vox, .qb or .schem",
            )),
        }
    }
}

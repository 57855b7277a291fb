//! The one error type of the brickmap crate. Every failure a user, a file or a thread can
//! cause is a value of this enum; the world is left unchanged whenever one is returned.

use glam::IVec3;

/// Everything that can go wrong in the brickmap crate.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BrickmapError {
    /// A grid dimension was zero or beyond the supported maximum.
    #[error("grid of {x}×{y}×{z} bricks is not supported (each axis 1..={}, 1..={}, 1..={})", max[0], max[1], max[2])]
    GridSize {
        /// Requested bricks along x.
        x: u32,
        /// Requested bricks along y.
        y: u32,
        /// Requested bricks along z.
        z: u32,
        /// The most bricks along each axis.
        max: [u32; 3],
    },
    /// A voxel coordinate lies outside the grid.
    #[error("voxel {0} is outside the grid (0,0,0)..{1}")]
    OutOfRange(IVec3, IVec3),
    /// A shape parameter was NaN or infinite.
    #[error("{0} is not a finite number")]
    NotFinite(&'static str),
    /// A shape size was zero or negative.
    #[error("{what} must be positive, got {value}")]
    NonPositive {
        /// Which parameter.
        what: &'static str,
        /// Its value.
        value: f64,
    },
    /// A box whose minimum corner exceeds its maximum corner.
    #[error("box min {min} exceeds max {max}")]
    EmptyBox {
        /// Inclusive minimum corner.
        min: IVec3,
        /// Inclusive maximum corner.
        max: IVec3,
    },
    /// A shape needs more points than it was given.
    #[error("a {0} needs at least one point")]
    NoPoints(&'static str),
    /// A material index beyond the scene material table.
    #[error("material {index} is beyond the material table ({len} entries)")]
    MaterialIndex {
        /// The index used.
        index: u32,
        /// Entries in the table.
        len: usize,
    },
    /// The material table already holds 256 entries.
    #[error("the material table is full (256 entries)")]
    MaterialTableFull,
    /// A material table without entries.
    #[error("a material table needs at least one material")]
    EmptyTable,
    /// A parameter-table index beyond its 64 entries.
    #[error("parameter index {0} is beyond the 64-entry parameter table")]
    ParamIndex(u32),
    /// A material parameter outside its valid range.
    #[error("{what} = {value} is outside {range}")]
    ParamRange {
        /// Which parameter.
        what: &'static str,
        /// Its value.
        value: f32,
        /// The valid range, in words.
        range: &'static str,
    },
    /// A zero or non-finite ray direction, or a non-finite origin.
    #[error("invalid ray: {0}")]
    InvalidRay(&'static str),
    /// Invalid world configuration (worker count, bucket sizes).
    #[error("invalid configuration: {0}")]
    Config(String),
    /// The global brick or material address space is exhausted.
    #[error("out of {0} address space")]
    OutOfSpace(&'static str),
    /// A worker thread panicked while applying an edit; the message is the panic payload.
    #[error("worker {worker} panicked: {message}")]
    WorkerPanicked {
        /// Which worker.
        worker: usize,
        /// The panic message.
        message: String,
    },
    /// A worker thread is gone (it panicked earlier or the world is shutting down).
    #[error("worker {0} is no longer running")]
    WorkerGone(usize),
    /// An edit failed and putting back its other parts failed too: the world holds part of
    /// the edit. Both errors are kept.
    #[error("{cause}; rolling the edit back failed too ({rollback}): the world holds part of it")]
    RollbackFailed {
        /// Why the edit failed.
        cause: Box<BrickmapError>,
        /// Why the rollback failed.
        rollback: Box<BrickmapError>,
    },
    /// An inverse edit does not fit this world (wrong grid or stale state).
    #[error("inverse edit does not fit this world: {0}")]
    BadInverse(&'static str),
    /// An edit that only exists in the world's frame (a brick restore, a generator) was
    /// asked of an object's model.
    #[error("{0} cannot be carried into an object's frame")]
    NotInModelFrame(&'static str),
}

/// The crate's result type.
pub type Result<T, E = BrickmapError> = std::result::Result<T, E>;

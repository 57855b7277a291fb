//! The world on the GPU: the brickmap's five buffers (brick index, bricks, coarse grid,
//! material bytes, material tables) uploaded as they are, bound at 0..4 by every shader
//! (`shaders/brickmap.glsl`), in device-local memory through a staging copy. Incremental
//! updates (a staging ring fed by `World::take_dirty` + `WorldView::copy_gpu_range`) come next.

use super::buffer::HostBuffer;
use super::{GpuContext, GpuError};
use brickmap::{GpuBuffer, WorldView};

/// The world's five buffers on the GPU, bound at 0..4 by every shader.
pub struct GpuWorld {
    buffers: Vec<HostBuffer>,
    dims: [u32; 3],
    words_per_column: u32,
}

impl GpuWorld {
    /// Uploads a world's current buffers.
    pub fn upload(ctx: &GpuContext, view: &WorldView<'_>) -> Result<Self, GpuError> {
        let mut buffers = Vec::new();
        for (name, which) in [
            ("brick index", GpuBuffer::BrickIndex),
            ("bricks", GpuBuffer::Bricks),
            ("coarse", GpuBuffer::Coarse),
            ("material bytes", GpuBuffer::MaterialBytes),
            ("material tables", GpuBuffer::MaterialTables),
        ] {
            let bytes = view.gpu_image(which);
            match HostBuffer::upload(ctx, name, &bytes) {
                Ok(b) => {
                    buffers.push(b);
                }
                Err(e) => {
                    buffers.into_iter().for_each(|b| b.destroy(ctx));
                    return Err(e);
                }
            }
        }
        let dims = view.dims();
        Ok(Self {
            buffers,
            dims: dims.bricks().to_array(),
            words_per_column: dims.coarse_words_per_column() as u32,
        })
    }

    /// Frees the buffers.
    pub fn destroy(self, ctx: &GpuContext) {
        self.buffers.into_iter().for_each(|b| b.destroy(ctx));
    }
}

impl GpuWorld {
    /// The buffers in binding order.
    pub fn buffers(&self) -> Vec<&HostBuffer> {
        self.buffers.iter().collect()
    }
    /// Grid size in bricks.
    pub fn dims(&self) -> [u32; 3] {
        self.dims
    }
    /// Coarse words per coarse x-column.
    pub fn words_per_column(&self) -> u32 {
        self.words_per_column
    }
}

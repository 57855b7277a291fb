//! The renderer: Vulkan compute path tracer over the brickmap and the CPU reference
//! renderer. Empty until its issue lands; the crate exists so the workspace shape is fixed.

// First hits of a list of rays, in air or inside a medium (tests the traversal against
// brickmap::raycast).
// Keep in sync with render/src/vulkan/primary.rs.
#version 450
layout(local_size_x = 64) in;

#include "brickmap.glsl"

layout(std430, set = 0, binding = 5) readonly buffer Rays { vec4 rays[]; };   // origin, dir per ray
layout(std430, set = 0, binding = 6) writeonly buffer Hits { vec4 hits[]; };  // voxel.xyz (or -1), t

layout(push_constant) uniform Push { uvec3 dims; uint count; uint words_per_column; uint medium; } pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    g_dims = pc.dims;
    g_words_per_column = pc.words_per_column;
    ivec3 voxel;
    ivec3 normal;
    float t;
    if (trace_from_origin(rays[2 * i].xyz, rays[2 * i + 1].xyz, int(pc.medium) - 1, 1.0 / 0.0, voxel, normal, t)) {
        hits[i] = vec4(vec3(voxel), t);
    } else {
        hits[i] = vec4(-1.0);
    }
}

// First hits of a list of rays, in air or inside a medium (tests the traversal against
// brickmap::raycast).
// Keep in sync with render/src/vulkan/primary.rs.
#version 450
layout(local_size_x = 64) in;

#define COUNT_STEPS true
#include "brickmap.glsl"

layout(std430, set = 0, binding = 5) readonly buffer Rays { vec4 rays[]; };   // origin, dir per ray
// Two per ray: voxel.xyz (or -1), t; the normal of the face entered, the iteration caps hit.
layout(std430, set = 0, binding = 6) writeonly buffer Hits { vec4 hits[]; };

layout(push_constant) uniform Push { uvec3 dims; uint count; uint words_per_column; uint medium; } pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    g_dims = pc.dims;
    g_words_per_column = pc.words_per_column;
    ivec3 voxel;
    ivec3 normal;
    float t;
    g_capped = 0u;
    if (trace_any(rays[2 * i].xyz, rays[2 * i + 1].xyz, int(pc.medium) - 1, voxel, normal, t)) {
        hits[2 * i] = vec4(vec3(voxel), t);
        hits[2 * i + 1] = vec4(vec3(normal), float(g_capped));
    } else {
        hits[2 * i] = vec4(-1.0);
        hits[2 * i + 1] = vec4(0.0, 0.0, 0.0, float(g_capped));
    }
}

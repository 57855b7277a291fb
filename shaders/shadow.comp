// Traces the shadow rays trace.comp queued (shaders/shadow_queue.glsl), one per invocation,
// and adds the light of each unblocked one to its pixel's accumulation (and, for a ray from a
// light-sampling vertex, counts its outcome in the light visibility cache).
// Keep in sync with render/src/vulkan/trace.rs.
#version 450
#extension GL_EXT_shader_atomic_float : require
layout(local_size_x = 64) in;

layout(constant_id = 0) const bool COUNT_RAYS = false;
// trace.comp's benchmark experiment bits; bit 4 skips this pass's work (to time the trace
// pass alone).
layout(constant_id = 1) const uint EXPERIMENT = 0u;
// trace.comp's LIGHTS: rays towards emissive faces may end in their light's voxel.
layout(constant_id = 2) const bool LIGHTS = false;

// Shadow rays travel in air.
#define MEDIUM_POSSIBLE false
#define COUNT_STEPS COUNT_RAYS
#define SKIPS_OFF ((EXPERIMENT >> 7) & 15u)
#define PAD_STEPS ((EXPERIMENT & 32u) != 0u)
#define PAD_LOAD ((EXPERIMENT & 32768u) != 0u)
// trace.comp's: used only where LIGHTS holds.
#define LIGHT_CACHE_ON ((EXPERIMENT & 262144u) != 0u)
#include "brickmap.glsl"

// The trace pass's bindings: only the grid size (Params.grid) is read here.
layout(std430, set = 0, binding = 5) readonly buffer ParamBuffer { vec4 params[14]; };
layout(std430, set = 0, binding = 6) buffer Accum { vec4 accum[]; };
layout(std430, set = 0, binding = 7) buffer Counters { uint counters[11]; };
#include "shadow_queue.glsl"
#include "lights.glsl"

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= min(queue_count, uint(shadow_rays.length())) || (EXPERIMENT & 16u) != 0u) return;
    uvec4 grid = floatBitsToUint(params[11]);
    g_dims = grid.xyz;
    g_words_per_column = grid.w;
    ShadowRay r = shadow_rays[i];
    uint key = floatBitsToUint(r.dir_key.w);
    uint pixel = key & ((1u << PIXEL_BITS) - 1u);
    uint off = (key >> PIXEL_BITS) & 31u;
    ivec3 cell = ivec3(floor(r.origin_t.xyz)) + ivec3(off % 3u, (off / 3u) % 3u, off / 9u) - 1;
    g_steps = 0u;
    g_capped = 0u;
    ivec3 voxel;
    ivec3 normal;
    float t;
    bool blocked = trace(r.origin_t.xyz, r.dir_key.xyz, false, 0.0, cell, AIR, r.origin_t.w, voxel, normal, t);
    uint light_slot = floatBitsToUint(r.light.w);
    if (LIGHTS && blocked && light_slot != NO_LIGHT) {
        // An emissive face's shadow ray may end in the light's voxel.
        ivec3 target;
        uint face;
        int material;
        light_face(light_slot, target, face, material);
        blocked = voxel != target;
    }
    // The ray counts in the light visibility cache at the entry of its first cell.
    if (LIGHTS && (key >> 31) != 0u) cache_record(cache_entry(cell), light_slot, !blocked);
    if (COUNT_RAYS) {
        atomicAdd(counters[5], g_steps);
        atomicMax(counters[7], g_steps);
        if (g_capped != 0u) atomicAdd(counters[8], g_capped);
    }
    if (!blocked) {
        atomicAdd(accum[pixel].x, r.light.x);
        atomicAdd(accum[pixel].y, r.light.y);
        atomicAdd(accum[pixel].z, r.light.z);
    }
}

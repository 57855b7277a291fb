// The queue of deferred shadow rays (trace.comp writes it, shadow.comp traces it). Bindings 8
// and 9; the header is also the indirect dispatch of shadow.comp (groups of 64), reset to
// (0, 1, 1, 0) before each trace dispatch. Keep in sync with render/src/vulkan/trace.rs.

// Origin and length, direction and packed pixel / first cell, radiance if unblocked and (w)
// the light slot of the emissive face the ray may end in (NO_LIGHT for the sun).
struct ShadowRay { vec4 origin_t; vec4 dir_key; vec4 light; };
const uint NO_LIGHT = 0xFFFFFFFFu;
layout(std430, set = 0, binding = 8) buffer ShadowRays { ShadowRay shadow_rays[]; };
layout(std430, set = 0, binding = 9) buffer ShadowQueue {
    uint queue_groups; // workgroups of shadow.comp (x of the indirect dispatch)
    uint queue_y;
    uint queue_z;
    uint queue_count;  // rays pushed, including any that did not fit
};

const uint PIXEL_BITS = 26u;

// Stores a shadow ray at `slot`: its first cell as an offset in {-1, 0, 1}³ from the cell
// holding its origin, with the pixel and (bit 31) whether its outcome counts in the light
// visibility cache (at the entry of that first cell), in one word. False when it does not fit
// (queue full, pixel index too large, or the offset out of range): the caller traces it itself.
bool push_shadow_ray(uint slot, vec3 o, ivec3 cell, vec3 d, float t, vec3 light, uint light_slot, uint pixel, bool cached) {
    ivec3 off = cell - ivec3(floor(o)) + 1;
    if (slot >= uint(shadow_rays.length()) || pixel >= (1u << PIXEL_BITS)
        || any(lessThan(off, ivec3(0))) || any(greaterThan(off, ivec3(2)))) return false;
    uint key = pixel | (uint(off.x + 3 * off.y + 9 * off.z) << PIXEL_BITS) | (cached ? 0x80000000u : 0u);
    shadow_rays[slot] = ShadowRay(vec4(o, t), vec4(d, uintBitsToFloat(key)), vec4(light, uintBitsToFloat(light_slot)));
    return true;
}

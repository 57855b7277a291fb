// The light visibility cache's factors (shaders/lights.glsl `LightCache`), before each trace
// dispatch of a light-sampling variant: one workgroup per entry, one invocation per node of the
// cached level. Counts gathered under another tree capacity, or in a world that has changed
// since (push constant), are dropped; counts past CACHE_KEEP tries are halved, so the cache follows
// edits. A node's factor is its share of unblocked rays with one of two for a prior, at least
// CACHE_LEAST: never zero, so every light keeps a positive probability.
// Keep in sync with render/src/vulkan/trace/light_cache.rs.
#version 450
layout(local_size_x = 64) in; // CACHE_NODES
layout(push_constant) uniform Push { uint reset; };
#define LIGHT_CACHE_ON true
#include "lights.glsl"

const uint CACHE_KEEP = 1024u;
const float CACHE_LEAST = 0.01;

float factor(uint unblocked, uint tries) {
    return max(CACHE_LEAST, (float(unblocked) + 1.0) / (float(tries) + 2.0));
}

shared uint s_tries[CACHE_NODES];
shared uint s_hits[CACHE_NODES];

void main() {
    uint base = gl_WorkGroupID.x * CACHE_WORDS;
    uint j = gl_LocalInvocationID.x;
    uint c = light_capacity();
    uint depth = uint(findMSB(c));
    uint level = cache_level(depth);
    uint coarse = cache_coarse_level(depth);
    bool stale = reset != 0u || light_cache[base + CACHE_CAPACITY] != c;
    barrier();
    uint tries = 0u;
    uint hits = 0u;
    if (!stale && j < (1u << level)) {
        tries = light_cache[base + j];
        hits = light_cache[base + CACHE_HITS + j];
        if (tries > CACHE_KEEP) {
            tries >>= 1;
            hits >>= 1;
        }
    }
    light_cache[base + j] = tries;
    light_cache[base + CACHE_HITS + j] = hits;
    light_cache[base + CACHE_FACTORS + j] = floatBitsToUint(factor(hits, tries));
    s_tries[j] = tries;
    s_hits[j] = hits;
    barrier();
    uint span = 1u << (level - coarse);
    if (j < (1u << coarse)) {
        uint t = 0u;
        uint h = 0u;
        for (uint k = j * span; k < (j + 1u) * span; k++) {
            t += s_tries[k];
            h += s_hits[k];
        }
        light_cache[base + CACHE_COARSE + j] = floatBitsToUint(factor(h, t));
    }
    if (j == 0u) {
        uint t = 0u;
        uint h = 0u;
        for (uint k = 0u; k < CACHE_NODES; k++) {
            t += s_tries[k];
            h += s_hits[k];
        }
        light_cache[base + CACHE_FACES] = floatBitsToUint(factor(h, t));
        uint st = stale ? 0u : light_cache[base + CACHE_SUN];
        uint sh = stale ? 0u : light_cache[base + CACHE_SUN + 1u];
        if (st > CACHE_KEEP) {
            st >>= 1;
            sh >>= 1;
        }
        light_cache[base + CACHE_SUN] = st;
        light_cache[base + CACHE_SUN + 1u] = sh;
        light_cache[base + CACHE_FACES + 1u] = floatBitsToUint(factor(sh, st));
        light_cache[base + CACHE_CAPACITY] = c;
    }
}

// The light faces of emissive voxels (brickmap/src/lights/: layout, weights, the light tree's
// bounds and importance, the face → slot table), binding 10. A face is chosen by descending
// the tree from the root by each child's importance from the shading point, exactly as
// `Lights::sample_from` does on the CPU (in f64 there), times the light visibility cache's
// factors (below; the GPU's alone). Keep in sync with both.
layout(std430, set = 0, binding = 10) readonly buffer LightFaces { uint light_words[]; };

const uint LIGHT_WEIGHTS = 4u;  // 256 f32 material weights after the 4-word header
const uint LIGHT_NODES = 260u;  // 2C f32 nodes: root 1, children 2i and 2i + 1, leaves C..2C
// Then 2C node bounds of 4 words, C face records of 2 words, the table's 2C words.

uint light_capacity() { return light_words[0]; }
float light_node(uint i) { return uintBitsToFloat(light_words[LIGHT_NODES + i]); }
float light_total() { return light_node(1u); }
float light_weight(int material) { return uintBitsToFloat(light_words[LIGHT_WEIGHTS + uint(material)]); }
uint light_faces_at() { return LIGHT_NODES + 10u * light_capacity(); }

// The light visibility cache (an experiment: trace.comp's EXPERIMENT bit 18;
// render/src/vulkan/trace/light_cache.rs), binding 11: for each
// of its entries (cache_entries(): 8192 where the device's limits allow, a power of two) for
// cells of space (8³-voxel blocks, hashed), how often shadow rays from there
// towards the lights under each tree node of the cached level reached their light, and the
// factors learned from those counts (shaders/light_cache.comp, before each trace dispatch). The
// descent multiplies the importance of the nodes at its first two step levels (3 and 6, or the
// tree's depth) by their factors, and the sun-or-faces share weighs both estimates by theirs:
// a deterministic, positive function of the point for a whole dispatch, so sampling and the MIS
// probability of a light face hit by a BSDF ray agree and every estimate stays unbiased.
// Entry words, from the constants below: tries and unblocked rays per node of the cached level,
// the sun's two, those nodes' factors, the coarse level's, the faces' (all nodes), the sun's,
// and last the capacity the counts were gathered under.
layout(std430, set = 0, binding = 11) buffer LightCache { uint light_cache[]; };
const uint CACHE_WORDS = 256u;
const uint CACHE_NODES = 64u;        // nodes of the cached level at most (level 6)
const uint CACHE_HITS = 64u;         // [CACHE_HITS, +64): unblocked rays ([0, 64): tries)
const uint CACHE_SUN = 128u;         // the sun's tries, then its unblocked rays
const uint CACHE_FACTORS = 160u;     // [CACHE_FACTORS, +64): the cached level's factors
const uint CACHE_COARSE = 224u;      // [CACHE_COARSE, +8): the coarse level's factors
const uint CACHE_FACES = 232u;       // the faces' factor, then the sun's
const uint CACHE_CAPACITY = 255u;
const uint NO_ENTRY = 0xFFFFFFFFu;
#ifndef LIGHT_CACHE_ON
#define LIGHT_CACHE_ON false
#endif

uint light_mix(uint x);

uint cache_entries() { return uint(light_cache.length()) / CACHE_WORDS; }

// The cached level (counts and factors) and the coarse level (factors) of a tree of `depth`.
uint cache_level(uint depth) { return min(6u, depth); }
uint cache_coarse_level(uint depth) { return min(3u, depth); }

// The cache entry of a vertex whose shadow rays start in voxel `front` (the air voxel before
// its face), or NO_ENTRY with the cache off.
uint cache_entry(ivec3 front) {
    if (!LIGHT_CACHE_ON) return NO_ENTRY;
    uvec3 b = uvec3(front >> 3);
    return light_mix(b.x ^ light_mix(b.y ^ light_mix(b.z + 0x9e3779b9u))) & (cache_entries() - 1u);
}

// The factor of tree node `node`'s importance at `entry` (1 at uncached levels).
float cache_factor(uint entry, uint node) {
    if (!LIGHT_CACHE_ON || entry == NO_ENTRY) return 1.0;
    uint depth = uint(findMSB(light_capacity()));
    uint level = uint(findMSB(node));
    uint base = entry * CACHE_WORDS;
    if (level == cache_level(depth) && level > 0u) return uintBitsToFloat(light_cache[base + CACHE_FACTORS + node - (1u << level)]);
    if (level == cache_coarse_level(depth) && level > 0u) return uintBitsToFloat(light_cache[base + CACHE_COARSE + node - (1u << level)]);
    return 1.0;
}

// The factors of the faces' and the sun's estimates in the sun-or-faces share.
float cache_faces_factor(uint entry) {
    return LIGHT_CACHE_ON && entry != NO_ENTRY ? uintBitsToFloat(light_cache[entry * CACHE_WORDS + CACHE_FACES]) : 1.0;
}
float cache_sun_factor(uint entry) {
    return LIGHT_CACHE_ON && entry != NO_ENTRY ? uintBitsToFloat(light_cache[entry * CACHE_WORDS + CACHE_FACES + 1u]) : 1.0;
}

// Counts a shadow ray from `entry` towards light slot `slot` (NO_LIGHT: the sun).
void cache_record(uint entry, uint slot, bool unblocked) {
    if (!LIGHT_CACHE_ON || entry == NO_ENTRY) return;
    uint base = entry * CACHE_WORDS;
    uint tries;
    uint hits;
    if (slot == 0xFFFFFFFFu) {
        tries = base + CACHE_SUN;
        hits = tries + 1u;
    } else {
        uint c = light_capacity();
        uint depth = uint(findMSB(c));
        uint level = cache_level(depth);
        tries = base + ((c + slot) >> (depth - level)) - (1u << level);
        hits = tries + CACHE_HITS;
    }
    atomicAdd(light_cache[tries], 1u);
    if (unblocked) atomicAdd(light_cache[hits], 1u);
}

// Benchmark only (trace.comp's EXPERIMENT bit 11): faces chosen by weight alone, the tree's
// bounds ignored (and the sun and the faces half each), as before the light tree.
#ifndef LIGHTS_BY_WEIGHT
#define LIGHTS_BY_WEIGHT false
#endif

// Node i's importance from point p with axis normal n (tree.rs `importance`): 0 exactly when
// none of its faces can light p.
float light_importance(uint i, vec3 p, ivec3 n) {
    float w = light_node(i);
    uint at = LIGHT_NODES + 2u * light_capacity() + 4u * i;
    uint mask = light_words[at + 3u];
    if (mask == 0u || !(w > 0.0)) return 0.0;
    if (LIGHTS_BY_WEIGHT) return w;
    uvec3 b = uvec3(light_words[at], light_words[at + 1u], light_words[at + 2u]);
    vec3 lo = vec3(b & 0xFFFFu);
    vec3 hi = vec3(b >> 16) + 1.0;
    vec3 v = p - (lo + hi) * 0.5;
    // +axis faces lie on planes from lo + 1 up, −axis faces on planes up to hi − 1.
    bvec3 pos = bvec3(uvec3(mask >> 1, mask >> 3, mask >> 5) & 1u);
    bvec3 neg = bvec3(uvec3(mask, mask >> 2, mask >> 4) & 1u);
    bvec3 pos_ok = bvec3(uvec3(pos) & uvec3(greaterThan(p, lo + 1.0)));
    bvec3 neg_ok = bvec3(uvec3(neg) & uvec3(lessThan(p, hi - 1.0)));
    const float NONE = -1.0 / 0.0;
    vec3 best3 = max(mix(vec3(NONE), v, pos_ok), mix(vec3(NONE), -v, neg_ok));
    float best = max(best3.x, max(best3.y, best3.z));
    if (best == NONE) return 0.0;
    vec3 nf = vec3(n);
    vec3 corner = mix(lo, hi, greaterThan(nf, vec3(0.0)));
    if (!(dot(nf, corner - p) > 0.0)) return 0.0;
    vec3 e = hi - lo;
    float r2 = dot(e, e) * 0.25;
    float d2 = dot(v, v);
    // The cosines towards the centre widened by r / d (tree.rs `widened`).
    float inv_d = inversesqrt(max(d2, 1e-20));
    float rd = 0.5 * length(e) * inv_d;
    float cl = clamp(best * inv_d + rd, 1e-4, 1.0);
    float cr = clamp(-dot(v, nf) * inv_d + rd, 1e-4, 1.0);
    return w * cl * cr / max(d2, r2);
}

// The descent takes LIGHT_LEVELS levels of the binary tree a step, choosing among a node's
// 2^LIGHT_LEVELS descendants that many levels down by their own importance: an 8-wide tree over
// the same nodes (tree.rs `DESCENT_LEVELS`, 3), the levels between unread. trace.comp's
// EXPERIMENT bits 16..17 choose 2 or 1 (the binary descent) for the benchmark.
#ifndef LIGHT_LEVELS
#define LIGHT_LEVELS 3u
#endif
const uint LIGHT_WIDE = 8u; // the widest step's children (LIGHT_LEVELS ≤ 3)

// The levels the step from depth d takes in a tree of `depth` levels.
uint light_step(uint d, uint depth) { return min(min(LIGHT_LEVELS, 3u), depth - d); }

// The slot chosen for p with normal n from u ∈ [0, 1) (rescaled at each step) and its
// probability, or NO_LIGHT when no face can light p.
uint sample_light(float u, vec3 p, ivec3 n, uint entry, out float prob) {
    prob = 0.0;
    uint c = light_capacity();
    uint i = 1u;
    float pr = 1.0;
    if (LIGHT_LEVELS == 1u) {
        while (i < c) {
            float l = light_importance(2u * i, p, n) * cache_factor(entry, 2u * i);
            float r = light_importance(2u * i + 1u, p, n) * cache_factor(entry, 2u * i + 1u);
            if (!(l + r > 0.0)) return 0xFFFFFFFFu;
            float pl = l / (l + r);
            if (u < pl) {
                u /= pl;
                pr *= pl;
                i = 2u * i;
            } else {
                u = (u - pl) / (1.0 - pl);
                pr *= 1.0 - pl;
                i = 2u * i + 1u;
            }
            u = min(u, 0.99999994);
        }
        prob = pr;
        return i - c;
    }
    uint depth = uint(findMSB(c));
    for (uint d = 0u; d < depth;) {
        uint s = light_step(d, depth);
        uint k = 1u << s;
        uint first = i << s;
        float imp[LIGHT_WIDE];
        float sum = 0.0;
        for (uint j = 0u; j < LIGHT_WIDE; j++) {
            imp[j] = j < k ? light_importance(first + j, p, n) * cache_factor(entry, first + j) : 0.0;
            sum += imp[j];
        }
        if (!(sum > 0.0)) return 0xFFFFFFFFu;
        // The child whose share of [0, sum) holds u · sum: the last of positive importance
        // whose share starts at or below it (the first positive one always does).
        float target = u * sum;
        float below = 0.0;
        uint pick = 0u;
        float below_pick = 0.0;
        float w = 0.0;
        for (uint j = 0u; j < LIGHT_WIDE; j++) {
            if (imp[j] > 0.0 && below <= target) {
                pick = j;
                below_pick = below;
                w = imp[j];
            }
            below += imp[j];
        }
        u = clamp((target - below_pick) / w, 0.0, 0.99999994);
        pr *= w / sum;
        i = first + pick;
        d += s;
    }
    prob = pr;
    return i - c;
}

// The probability that sample_light at p with normal n chooses `slot` (the caller knows the
// root's importance is positive).
float light_probability(uint slot, vec3 p, ivec3 n, uint entry) {
    uint c = light_capacity();
    uint leaf = c + slot;
    float pr = 1.0;
    if (LIGHT_LEVELS == 1u) {
        for (uint level = uint(findMSB(c)); level > 0u; level--) {
            uint parent = leaf >> level;
            float l = light_importance(2u * parent, p, n) * cache_factor(entry, 2u * parent);
            float r = light_importance(2u * parent + 1u, p, n) * cache_factor(entry, 2u * parent + 1u);
            if (!(l + r > 0.0)) return 0.0;
            pr *= (((leaf >> (level - 1u)) & 1u) == 0u ? l : r) / (l + r);
        }
        return pr;
    }
    uint depth = uint(findMSB(c));
    for (uint d = 0u; d < depth;) {
        uint s = light_step(d, depth);
        uint k = 1u << s;
        uint first = (leaf >> (depth - d)) << s;
        uint on = (leaf >> (depth - d - s)) - first;
        float sum = 0.0;
        float w = 0.0;
        for (uint j = 0u; j < LIGHT_WIDE; j++) {
            float x = j < k ? light_importance(first + j, p, n) * cache_factor(entry, first + j) : 0.0;
            sum += x;
            w = j == on ? x : w;
        }
        if (!(sum > 0.0)) return 0.0;
        pr *= w / sum;
        d += s;
    }
    return pr;
}

// A slot's face: its voxel, which face (−x, +x, −y, +y, −z, +z) and the voxel's material.
void light_face(uint slot, out ivec3 voxel, out uint face, out int material) {
    uint at = light_faces_at() + 2u * slot;
    uint w0 = light_words[at];
    uint w1 = light_words[at + 1u];
    voxel = ivec3(int(w0 & 0xFFFu), int(w1 & 0xFFFFu), int((w0 >> 12) & 0xFFFu));
    face = (w0 >> 24) & 7u;
    material = int(w1 >> 16);
}

uint light_mix(uint x) {
    x = x * 747796405u + 2891336453u;
    x = ((x >> ((x >> 28u) + 4u)) ^ x) * 277803737u;
    return (x >> 22u) ^ x;
}

// The slot of the light face (voxel, face), or 0xFFFFFFFF (lookup.rs `FaceTable::find`).
uint light_slot_of(ivec3 voxel, uint face) {
    uint c = light_capacity();
    uint w0 = uint(voxel.x) | (uint(voxel.z) << 12) | (face << 24);
    uint y = uint(voxel.y);
    uint faces = light_faces_at();
    uint table = faces + 2u * c;
    uint mask = 2u * c - 1u;
    uint i = light_mix(w0 ^ light_mix(y)) & mask;
    for (uint k = 0u; k <= mask; k++) {
        uint e = light_words[table + i];
        if (e == 0u) break;
        uint at = faces + 2u * (e - 1u);
        if (light_words[at] == w0 && (light_words[at + 1u] & 0xFFFFu) == y) return e - 1u;
        i = (i + 1u) & mask;
    }
    return 0xFFFFFFFFu;
}

vec3 face_normal(uint face) {
    vec3 n = vec3(0.0);
    n[face >> 1] = (face & 1u) != 0u ? 1.0 : -1.0;
    return n;
}

// The face index (−x, +x, −y, +y, −z, +z) of an axis normal.
uint face_of(ivec3 n) {
    return n.x != 0 ? (n.x > 0 ? 1u : 0u) : (n.y != 0 ? (n.y > 0 ? 3u : 2u) : (n.z > 0 ? 5u : 4u));
}

// The point (u1, u2) of a voxel's face (render/src/cpu/mod.rs `face_point`).
vec3 face_point(ivec3 voxel, uint face, float u1, float u2) {
    float high = float(face & 1u);
    uint axis = face >> 1;
    vec3 o = axis == 0u ? vec3(high, u1, u2) : (axis == 1u ? vec3(u1, high, u2) : vec3(u1, u2, high));
    return vec3(voxel) + o;
}

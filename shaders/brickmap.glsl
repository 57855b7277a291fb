// The brickmap on the GPU and its traversal: the same event rule as brickmap::raycast
// (half-open voxels, crossing times (b − o)/d, positive axes step before negative ones at a
// tie, coarse and brick skipping, full cells), in f32, plus skipping of empty 4³ and 2³
// blocks inside bricks (the same event rule at their planes, so the same hits). Layouts:
// docs/DESIGN.md "GPU-facing layout of the world"; keep in sync with brickmap/src/{brick,grid,material}.rs
// and render/src/vulkan/world.rs. Every shader binds the world at 0..4; its own buffers start
// at 5.

struct Brick { uint mask[16]; uint material; };

layout(std430, set = 0, binding = 0) readonly buffer BrickIndex { uint brick_index[]; };
layout(std430, set = 0, binding = 1) readonly buffer Bricks { Brick bricks[]; };
layout(std430, set = 0, binding = 2) readonly buffer Coarse { uint coarse[]; };
layout(std430, set = 0, binding = 3) readonly buffer MaterialBytes { uint material_bytes[]; };
layout(std430, set = 0, binding = 4) readonly buffer MaterialTables {
    uint packed_materials[128];
    uint colours[256];
    float roughness[64];
    float ior[64];
    float strength[64];
} tables;

// A shader that never traces inside a dielectric defines MEDIUM_POSSIBLE false.
#ifndef MEDIUM_POSSIBLE
#define MEDIUM_POSSIBLE true
#endif

// A shader that counts traversal steps (into g_steps) defines COUNT_STEPS true.
#ifndef COUNT_STEPS
#define COUNT_STEPS false
#endif
uint g_steps;

// Benchmark only (`voxbrick bench-skips`): skips turned off, bit 0 the coarse grid's, bit 1
// the 4³ / 2³ blocks inside bricks, bit 2 a brick full of the medium inside a dielectric,
// bit 3 full cells read as stored bricks would be (their mask words loaded). trace.comp and
// shadow.comp define it from their EXPERIMENT bits 7..10; 0 everywhere else.
#ifndef SKIPS_OFF
#define SKIPS_OFF 0u
#endif
// Benchmark only (`bench-gpu --experiment`): 64 extra multiply-adds per traversal step
// (PAD_STEPS) or one extra load the step's end waits for (PAD_LOAD): is a step's time set by
// its instructions or by its loads? Measured on the H100 (BENCHMARKS.md "The renderer, round
// 5"): the multiply-adds cost complexities 1 / 2 / 3 +1 / +5 / +5 %, the load +12 / +17 /
// +19 %. trace.comp and shadow.comp define them from their EXPERIMENT bits 5 and 15.
#ifndef PAD_STEPS
#define PAD_STEPS false
#endif
#ifndef PAD_LOAD
#define PAD_LOAD false
#endif
// COUNT_STEPS shaders only: iteration caps hit (a traversal that ran out of its step budget,
// a cell_at that ran out of its corrections); every one is a bug (`voxbrick stress`).
uint g_capped;

const uint EMPTY = 0xFFFFFFFFu;
const uint FULL_BASE = 0xFFFFFE00u;
const uint UNIFORM_FLAG = 0x80000000u;
const int AIR = -1;

uvec3 g_dims;            // grid size in bricks
uint g_words_per_column; // coarse words per coarse x-column
vec3 g_o;                // current ray
vec3 g_d;
ivec3 g_sgn;
ivec3 g_size;

// Per-axis access by selects, never by a dynamic vector index: a dynamically indexed vector
// lives in local memory on NVIDIA (measured: 300–500 bytes of local memory per invocation
// before this was written so).
float comp(vec3 v, int a) { return a == 0 ? v.x : (a == 1 ? v.y : v.z); }
int comp(ivec3 v, int a) { return a == 0 ? v.x : (a == 1 ? v.y : v.z); }

float plane_time(int axis, float b) { return (b - comp(g_o, axis)) / comp(g_d, axis); }

uint cell_word(ivec3 b) { return brick_index[(uint(b.x) * g_dims.z + uint(b.z)) * g_dims.y + uint(b.y)]; }

bool coarse_occupied(ivec3 c) {
    uvec3 cd = (g_dims + 3u) / 4u;
    uint within = uint(c.z) * cd.y + uint(c.y);
    uint word = uint(c.x) * g_words_per_column + within / 32u;
    return ((coarse[word] >> (within % 32u)) & 1u) != 0u;
}

// Inside stored brick w: log2 of the empty block around voxel v that the traversal may skip
// (2: the voxel's 4³ quarter of the brick is empty, 1: its 2³ block is), else 0 with `hit`
// saying whether the voxel is solid. Mask bit x + 8y + 64z lies in word y/4 + 2z, so a 4³
// quarter is bits 0x0F0F0F0F << (x & 4) of four words two apart, a 2³ block bits 0x303 of
// two of them. Measured on the H100 (thesis scene): complexity 1 / 2 / 3 0.340 / 0.487 /
// 1.56 ms without these levels, 0.285 / 0.409 / 1.33 with 2³ blocks alone, 0.256 / 0.364 /
// 1.20 with both.
int brick_block(uint w, ivec3 v, out bool hit) {
    hit = false;
    ivec3 l = v & 7;
    uint k = uint((l.y >> 2) + 2 * (l.z & 4));
    uint a0 = bricks[w].mask[k];
    uint a1 = bricks[w].mask[k + 2u];
    uint a2 = bricks[w].mask[k + 4u];
    uint a3 = bricks[w].mask[k + 6u];
    if ((((a0 | a1 | a2 | a3) >> uint(l.x & 4)) & 0x0F0F0F0Fu) == 0u) return 2;
    bool upper = (l.z & 2) != 0;
    uint m0 = upper ? a2 : a0; // layer z & 6
    uint m1 = upper ? a3 : a1; // layer (z & 6) + 1
    uint row = uint(8 * (l.y & 3));
    if ((((m0 | m1) >> (uint(l.x & 6) + (row & 16u))) & 0x303u) == 0u) return 1;
    hit = ((((l.z & 1) == 0 ? m0 : m1) >> (uint(l.x) + row)) & 1u) != 0u;
    return 0;
}

// Whether voxel v of stored brick w is solid (its mask bit alone).
bool voxel_bit(uint w, ivec3 v) {
    ivec3 l = v & 7;
    uint bit = uint(l.x + 8 * l.y + 64 * l.z);
    return ((bricks[w].mask[bit >> 5] >> (bit & 31u)) & 1u) != 0u;
}

// Material of voxel v of the cell whose brick-index word is w, or -1 when empty. Brick fields
// are read from the buffer where needed; copying the Brick to a local made a 68-byte
// local-memory array (the two were equally fast on the H100, and this one uses no local
// memory at all).
int material_in(uint w, ivec3 v) {
    if (w == EMPTY) return -1;
    if (w >= FULL_BASE) return int(w & 0xFFu);
    if (!voxel_bit(w, v)) return -1;
    ivec3 l = v & 7;
    uint bit = uint(l.x + 8 * l.y + 64 * l.z);
    uint material = bricks[w].material;
    if ((material & UNIFORM_FLAG) != 0u) return int(material & 0xFFu);
    uint rank = 0u;
    for (uint k = 0u; k < (bit >> 5); k++) rank += uint(bitCount(bricks[w].mask[k]));
    rank += uint(bitCount(bricks[w].mask[bit >> 5] & ((1u << (bit & 31u)) - 1u)));
    uint at = material + rank;
    return int((material_bytes[at >> 2] >> (8u * (at & 3u))) & 0xFFu);
}

// Material of voxel v (inside the grid), or -1 when empty.
int material_at(ivec3 v) { return material_in(cell_word(v >> 3), v); }

int cell_at(int axis, float t, bool after) {
    int sgn = comp(g_sgn, axis);
    float o = comp(g_o, axis);
    if (sgn == 0) return int(floor(o));
    int n = comp(g_size, axis);
    int c = clamp(int(floor(o + t * comp(g_d, axis))), -1, n);
    int k = 0;
    for (; k < 8; k++) {
        if (sgn > 0) {
            if (c < n && plane_time(axis, float(c + 1)) <= t) { c++; continue; }
            if (c > -1 && plane_time(axis, float(c)) > t) { c--; continue; }
        } else {
            bool up = after ? plane_time(axis, float(c + 1)) > t : plane_time(axis, float(c + 1)) >= t;
            bool here = after ? plane_time(axis, float(c)) > t : plane_time(axis, float(c)) >= t;
            if (c < n && up) { c++; continue; }
            if (c > -1 && !here) { c--; continue; }
        }
        break;
    }
    if (COUNT_STEPS && k == 8) g_capped++;
    return c;
}

void set_ray(vec3 o, vec3 d) {
    g_o = o;
    g_d = d;
    g_sgn = ivec3(sign(d));
    g_size = ivec3(g_dims) * 8;
}

// Walks from `cell` at time `t` to the first interaction: a solid voxel (medium AIR, with
// empty-space skipping) or a voxel that is not `medium` (inside a dielectric). Returns false
// when the ray leaves the grid or passes t_max. `axis` is the axis entered last (normal).
// Written with whole-vector operations (no per-axis indexing).
bool dda(ivec3 cell, float t, int axis, int medium, float t_max, out ivec3 voxel, out ivec3 normal, out float t_hit) {
    int budget = 3 * (g_size.x + g_size.y + g_size.z + 8);
    ivec3 forward = ivec3(greaterThan(g_sgn, ivec3(0)));
    ivec3 backward = ivec3(lessThan(g_sgn, ivec3(0)));
    bvec3 moving = notEqual(g_sgn, ivec3(0));
    for (int step = 0; step < budget; step++) {
        if (COUNT_STEPS) g_steps++;
        bool leaving = any(bvec3(forward * ivec3(greaterThanEqual(cell, g_size)) + backward * ivec3(lessThan(cell, ivec3(0)))));
        bool inside = all(greaterThanEqual(cell, ivec3(0))) && all(lessThan(cell, g_size));
        if (leaving || t > t_max) return false;
        int shift = 0; // log2 of the block size
        if (inside) {
            bool hit = false;
            if (!MEDIUM_POSSIBLE || medium == AIR) {
                // The cell's brick-index word is loaded with its coarse bit, not after it: one
                // dependent load fewer per step in occupied space, one load more per step in
                // empty space (measured on the H100: complexities 2 and 3 −1.1 %, 1 −0.4 %).
                uint w = cell_word(cell >> 3);
                if ((SKIPS_OFF & 1u) == 0u && !coarse_occupied(cell >> 5)) {
                    shift = 5;
                } else {
                    if (w == EMPTY) shift = 3;
                    else if (w >= FULL_BASE) {
                        hit = true;
                        if ((SKIPS_OFF & 8u) != 0u) {
                            // A stored brick's loads, from a brick near in memory the way a
                            // slab's bricks are (the result never changes: blocks are 0..2).
                            ivec3 b = cell >> 3;
                            uint probe = (uint(b.x) * g_dims.z + uint(b.z)) * g_dims.y + uint(b.y);
                            bool solid;
                            if (brick_block(probe % max(uint(bricks.length()), 1u), cell, solid) > 2) hit = solid;
                        }
                    }
                    else if ((SKIPS_OFF & 2u) != 0u) hit = voxel_bit(w, cell);
                    else shift = brick_block(w, cell, hit);
                }
            } else {
                // Inside a medium a brick full of it is skipped whole, like an empty brick in
                // air (the first voxel that is not the medium is found by the same event rule).
                uint w = cell_word(cell >> 3);
                if ((SKIPS_OFF & 4u) == 0u && w == FULL_BASE + uint(medium)) shift = 3;
                else hit = material_in(w, cell) != medium;
            }
            if (hit) {
                voxel = cell;
                int s = -comp(g_sgn, axis);
                normal = ivec3(axis == 0 ? s : 0, axis == 1 ? s : 0, axis == 2 ? s : 0);
                t_hit = t;
                return true;
            }
        }
        // Next planes of the current block (1, 2, 4, 8 or 32 voxels; shifts floor negatives too).
        ivec3 base = (cell >> shift) << shift;
        ivec3 bound = base + forward * (1 << shift);
        vec3 times = mix(vec3(1.0 / 0.0), (vec3(bound) - g_o) / g_d, moving);
        float t_next = min(times.x, min(times.y, times.z));
        if (PAD_STEPS) {
            vec4 a = vec4(t_next, t, times.x, times.y);
            for (int i = 0; i < 16; i++) a = a * 1.0000001 + 1e-7;
            if (a.x + a.y + a.z + a.w == -1.0) t_next = t;
        }
        if (PAD_LOAD) {
            // The brick-index word after this cell's (cached with it), at an address that
            // depends on the step's time so it cannot be loaded early.
            ivec3 b = cell >> 3;
            uint at = (uint(b.x) * g_dims.z + uint(b.z)) * g_dims.y + uint(b.y) + (t_next > -1.0 ? 1u : 2u);
            if (brick_index[at % uint(brick_index.length())] == 0xFFFFFFFEu) t_next = t;
        }
        if (isinf(t_next)) return false;
        bvec3 at_t = equal(times, vec3(t_next));
        bool positive_tie = any(bvec3(ivec3(at_t) * forward));
        bvec3 stepped = bvec3(ivec3(at_t) * (positive_tie ? forward : backward));
        cell = mix(cell, bound - backward, stepped);
        axis = stepped.z ? 2 : (stepped.y ? 1 : (stepped.x ? 0 : axis));
        if (shift > 0) {
            if (!stepped.x && moving.x) cell.x = cell_at(0, t_next, !positive_tie);
            if (!stepped.y && moving.y) cell.y = cell_at(1, t_next, !positive_tie);
            if (!stepped.z && moving.z) cell.z = cell_at(2, t_next, !positive_tie);
        }
        t = t_next;
    }
    if (COUNT_STEPS) g_capped++;
    return false;
}

// The axis whose entry plane into `cell` was crossed last (the face behind the origin).
int entry_axis(ivec3 cell) {
    int axis = g_sgn.x != 0 ? 0 : (g_sgn.y != 0 ? 1 : 2);
    float latest = -1.0 / 0.0;
    for (int a = 0; a < 3; a++) {
        int s = comp(g_sgn, a);
        if (s == 0) continue;
        int c = comp(cell, a);
        float e = plane_time(a, float(s > 0 ? c : c + 1));
        if (e > latest) { latest = e; axis = a; }
    }
    return axis;
}

// The time a ray from `o` enters the grid's box (0 inside it; infinite or NaN: never).
float entry_time(vec3 o) {
    float t = 0.0;
    for (int a = 0; a < 3; a++) {
        int s = comp(g_sgn, a);
        float oa = comp(o, a);
        float n = float(comp(g_size, a));
        if (s == 0) {
            if (!(oa >= 0.0 && oa < n)) return 1.0 / 0.0;
        } else {
            t = max(t, plane_time(a, s > 0 ? 0.0 : n));
        }
    }
    return t;
}

// Beyond this many voxels outside the grid trace_any first moves a ray's origin to just before
// the grid (as brickmap::Ray::near_grid does): crossing times from a far origin carry its f32
// rounding (half a voxel at 4·10⁶), and the walk's comparisons would order crossings wrongly.
const float FAR_ORIGIN = 1024.0;

// One entry for every ray, so a shader that calls only this has a single copy of the
// traversal: from anywhere (the camera; finds its first cell in the grid) when `from_origin`,
// else leaving a surface from the known `cell` at t = 0 (no epsilon offsets).
// From the origin the walk may start later, at `t_min`, when the caller knows no voxel lies
// before it (trace.comp's camera rays: their tile's march through the coarse grid).
bool trace(vec3 o, vec3 d, bool from_origin, float t_min, ivec3 cell, int medium, float t_max, out ivec3 voxel, out ivec3 normal, out float t_hit) {
    set_ray(o, d);
    float t = 0.0;
    if (from_origin) {
        t = entry_time(o);
        if (isinf(t) || isnan(t)) return false;
        t = max(t, t_min);
        cell = ivec3(cell_at(0, t, false), cell_at(1, t, false), cell_at(2, t, false));
    }
    return dda(cell, t, entry_axis(cell), medium, t_max, voxel, normal, t_hit);
}

// Direction components below f32's least normal count as zero (Vulkan lets a device flush
// denormals; trace_any flushes them itself, so all devices agree).
const float LEAST_NORMAL = 1.17549435e-38;

// `trace` from the origin for any finite ray (shaders/primary.comp, `voxbrick stress`):
// denormal direction components flushed; the direction scaled by a power of two (exact) so
// its largest component is in [0.5, 1) (crossing times of huge directions would underflow,
// of tiny ones overflow); an origin farther than FAR_ORIGIN outside the grid moved exactly
// to just before it. The path tracer's rays are unit vectors from nearby origins and skip
// this conditioning (measured: +7% GPU time on the thesis complexities 2 and 3 if every
// ray paid for it).
bool trace_any(vec3 o, vec3 d, int medium, out ivec3 voxel, out ivec3 normal, out float t_hit) {
    d = mix(d, vec3(0.0), lessThan(abs(d), vec3(LEAST_NORMAL)));
    vec3 ad = abs(d);
    float dmax = max(ad.x, max(ad.y, ad.z));
    int e = 0;
    frexp(dmax, e);
    d = ldexp(d, ivec3(-e));
    ad = abs(d);
    set_ray(o, d);
    float t = entry_time(o);
    if (isinf(t) || isnan(t)) return false;
    float shift = 0.0;
    vec3 outside = max(-o, o - vec3(g_size));
    if (max(outside.x, max(outside.y, outside.z)) > FAR_ORIGIN) {
        shift = max(t - 2.0 / max(ad.x, max(ad.y, ad.z)), 0.0);
        // o + shift·d without the rounding of o's magnitude: the product's and the sum's
        // errors recovered exactly (Dekker's product with Veltkamp's split, Knuth's two-sum;
        // `precise` forbids contraction and reassociation; Vulkan does not promise a fused
        // fma()) and added back near the grid. |d| < 1 here, so the split cannot overflow.
        precise vec3 prod = shift * d;
        precise float cs = 4097.0 * shift;
        precise float sh = cs - (cs - shift);
        precise float sl = shift - sh;
        precise vec3 cd = 4097.0 * d;
        precise vec3 dh = cd - (cd - d);
        precise vec3 dl = d - dh;
        precise vec3 prod_err = ((sh * dh - prod) + sh * dl + sl * dh) + sl * dl;
        precise vec3 sum = o + prod;
        precise vec3 bb = sum - o;
        precise vec3 sum_err = (o - (sum - bb)) + (prod - bb);
        precise vec3 near = sum + (prod_err + sum_err);
        set_ray(near, d);
        t = entry_time(g_o);
        if (isinf(t) || isnan(t)) return false;
    }
    ivec3 cell = ivec3(cell_at(0, t, false), cell_at(1, t, false), cell_at(2, t, false));
    bool hit = dda(cell, t, entry_axis(cell), medium, 1.0 / 0.0, voxel, normal, t_hit);
    t_hit = ldexp(t_hit + shift, -e);
    return hit;
}

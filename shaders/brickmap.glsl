// The brickmap on the GPU and its traversal: the same event rule as brickmap::raycast
// (half-open voxels, crossing times (b − o)/d, positive axes step before negative ones at a
// tie, coarse and brick skipping, full cells), in f32. Layouts: ARCHITECTURE.md "GPU-facing
// layout"; keep in sync with brickmap/src/{brick,grid,material}.rs and render/src/vulkan/world.rs.
// Every shader binds the world at 0..4; its own buffers start at 5.

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

float plane_time(int axis, float b) { return (b - g_o[axis]) / g_d[axis]; }

uint cell_word(ivec3 b) { return brick_index[(uint(b.x) * g_dims.z + uint(b.z)) * g_dims.y + uint(b.y)]; }

bool coarse_occupied(ivec3 c) {
    uvec3 cd = (g_dims + 3u) / 4u;
    uint within = uint(c.z) * cd.y + uint(c.y);
    uint word = uint(c.x) * g_words_per_column + within / 32u;
    return ((coarse[word] >> (within % 32u)) & 1u) != 0u;
}

// Material of voxel v (inside the grid), or -1 when empty.
int material_at(ivec3 v) {
    uint w = cell_word(v >> 3);
    if (w == EMPTY) return -1;
    if (w >= FULL_BASE) return int(w & 0xFFu);
    ivec3 l = v & 7;
    uint bit = uint(l.x + 8 * l.y + 64 * l.z);
    Brick b = bricks[w];
    if (((b.mask[bit >> 5] >> (bit & 31u)) & 1u) == 0u) return -1;
    if ((b.material & UNIFORM_FLAG) != 0u) return int(b.material & 0xFFu);
    uint rank = 0u;
    for (uint k = 0u; k < (bit >> 5); k++) rank += uint(bitCount(b.mask[k]));
    rank += uint(bitCount(b.mask[bit >> 5] & ((1u << (bit & 31u)) - 1u)));
    uint at = b.material + rank;
    return int((material_bytes[at >> 2] >> (8u * (at & 3u))) & 0xFFu);
}

bool solid_at(ivec3 v) {
    uint w = cell_word(v >> 3);
    if (w == EMPTY) return false;
    if (w >= FULL_BASE) return true;
    ivec3 l = v & 7;
    uint bit = uint(l.x + 8 * l.y + 64 * l.z);
    return ((bricks[w].mask[bit >> 5] >> (bit & 31u)) & 1u) != 0u;
}

int cell_at(int axis, float t, bool after) {
    if (g_sgn[axis] == 0) return int(floor(g_o[axis]));
    int n = g_size[axis];
    int c = clamp(int(floor(g_o[axis] + t * g_d[axis])), -1, n);
    for (int k = 0; k < 8; k++) {
        if (g_sgn[axis] > 0) {
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
bool dda(ivec3 cell, float t, int axis, int medium, float t_max, out ivec3 voxel, out ivec3 normal, out float t_hit) {
    int budget = 3 * (g_size.x + g_size.y + g_size.z + 8);
    for (int step = 0; step < budget; step++) {
        bool leaving = false;
        bool inside = true;
        for (int a = 0; a < 3; a++) {
            leaving = leaving || (g_sgn[a] > 0 && cell[a] >= g_size[a]) || (g_sgn[a] < 0 && cell[a] < 0);
            inside = inside && cell[a] >= 0 && cell[a] < g_size[a];
        }
        if (leaving || t > t_max) return false;
        int block = 1;
        if (inside) {
            bool hit;
            if (!MEDIUM_POSSIBLE || medium == AIR) {
                if (!coarse_occupied(cell >> 5)) block = 32;
                else if (cell_word(cell >> 3) == EMPTY) block = 8;
                hit = block == 1 && solid_at(cell);
            } else {
                hit = material_at(cell) != medium;
            }
            if (hit) {
                voxel = cell;
                normal = ivec3(0);
                normal[axis] = -g_sgn[axis];
                t_hit = t;
                return true;
            }
        }
        ivec3 bound = ivec3(0);
        vec3 times = vec3(1.0 / 0.0);
        float t_next = 1.0 / 0.0;
        for (int a = 0; a < 3; a++) {
            if (g_sgn[a] == 0) continue;
            int base = (cell[a] >= 0 ? cell[a] / block : (cell[a] - block + 1) / block) * block;
            bound[a] = g_sgn[a] > 0 ? base + block : base;
            times[a] = plane_time(a, float(bound[a]));
            t_next = min(t_next, times[a]);
        }
        if (isinf(t_next)) return false;
        bool positive_tie = false;
        for (int a = 0; a < 3; a++) positive_tie = positive_tie || (g_sgn[a] > 0 && times[a] == t_next);
        bvec3 stepped = bvec3(false);
        for (int a = 0; a < 3; a++) {
            if (g_sgn[a] != 0 && times[a] == t_next && (g_sgn[a] > 0) == positive_tie) {
                stepped[a] = true;
                cell[a] = g_sgn[a] > 0 ? bound[a] : bound[a] - 1;
                axis = a;
            }
        }
        if (block > 1) {
            for (int a = 0; a < 3; a++) {
                if (!stepped[a] && g_sgn[a] != 0) cell[a] = cell_at(a, t_next, !positive_tie);
            }
        }
        t = t_next;
    }
    return false;
}

// The axis whose entry plane into `cell` was crossed last (the face behind the origin).
int entry_axis(ivec3 cell) {
    int axis = g_sgn.x != 0 ? 0 : (g_sgn.y != 0 ? 1 : 2);
    float latest = -1.0 / 0.0;
    for (int a = 0; a < 3; a++) {
        if (g_sgn[a] == 0) continue;
        float e = plane_time(a, float(g_sgn[a] > 0 ? cell[a] : cell[a] + 1));
        if (e > latest) { latest = e; axis = a; }
    }
    return axis;
}

// A ray from anywhere (the camera): finds its first cell in the grid, then walks.
bool trace_from_origin(vec3 o, vec3 d, int medium, float t_max, out ivec3 voxel, out ivec3 normal, out float t_hit) {
    set_ray(o, d);
    float t = 0.0;
    for (int a = 0; a < 3; a++) {
        if (g_sgn[a] == 0) {
            if (!(o[a] >= 0.0 && o[a] < float(g_size[a]))) return false;
        } else {
            t = max(t, plane_time(a, g_sgn[a] > 0 ? 0.0 : float(g_size[a])));
        }
    }
    if (isinf(t) || isnan(t)) return false;
    ivec3 cell;
    for (int a = 0; a < 3; a++) cell[a] = cell_at(a, t, false);
    return dda(cell, t, entry_axis(cell), medium, t_max, voxel, normal, t_hit);
}

// A ray leaving a surface from a known cell (no epsilon offsets).
bool trace_from_cell(vec3 o, vec3 d, ivec3 cell, int medium, float t_max, out ivec3 voxel, out ivec3 normal, out float t_hit) {
    set_ray(o, d);
    return dda(cell, 0.0, entry_axis(cell), medium, t_max, voxel, normal, t_hit);
}

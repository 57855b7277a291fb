// First-hit traversal of rays through coarse grid → brick grid → voxels, the same event rule
// as brickmap::raycast (half-open voxels, crossing times (b − o)/d, positive axes step before
// negative ones at a tie, full cells hit at once), in f32. Buffer layouts: ARCHITECTURE.md
// "GPU-facing layout"; keep in sync with brickmap/src/{brick,grid}.rs and
// render/src/vulkan/primary.rs.
#version 450
layout(local_size_x = 64) in;

struct Brick { uint mask[16]; uint material; };

layout(std430, set = 0, binding = 0) readonly buffer BrickIndex { uint brick_index[]; };
layout(std430, set = 0, binding = 1) readonly buffer Bricks { Brick bricks[]; };
layout(std430, set = 0, binding = 2) readonly buffer Coarse { uint coarse[]; };
layout(std430, set = 0, binding = 3) readonly buffer Rays { vec4 rays[]; };     // origin, dir per ray
layout(std430, set = 0, binding = 4) writeonly buffer Hits { vec4 hits[]; };    // voxel.xyz (or -1), t

layout(push_constant) uniform Push {
    uvec3 dims;            // grid size in bricks
    uint count;            // rays
    uint words_per_column; // coarse words per coarse x-column
} pc;

const uint EMPTY = 0xFFFFFFFFu;
const uint FULL_BASE = 0xFFFFFE00u;

vec3 o;
vec3 d;
ivec3 sgn;
ivec3 size;

float plane_time(int axis, float b) { return (b - o[axis]) / d[axis]; }

uint cell_word(ivec3 b) { return brick_index[(uint(b.x) * pc.dims.z + uint(b.z)) * pc.dims.y + uint(b.y)]; }

bool coarse_occupied(ivec3 c) {
    uvec3 cd = (pc.dims + 3u) / 4u;
    uint within = uint(c.z) * cd.y + uint(c.y);
    uint word = uint(c.x) * pc.words_per_column + within / 32u;
    return ((coarse[word] >> (within % 32u)) & 1u) != 0u;
}

bool solid(ivec3 v) {
    uint w = cell_word(v >> 3);
    if (w == EMPTY) return false;
    if (w >= FULL_BASE) return true;
    ivec3 l = v & 7;
    uint bit = uint(l.x + 8 * l.y + 64 * l.z);
    return ((bricks[w].mask[bit >> 5] >> (bit & 31u)) & 1u) != 0u;
}

int cell_at(int axis, float t, bool after) {
    int n = size[axis];
    int c = clamp(int(floor(o[axis] + t * d[axis])), -1, n);
    if (sgn[axis] == 0) return int(floor(o[axis]));
    for (int k = 0; k < 8; k++) {
        if (sgn[axis] > 0) {
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

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    o = rays[2 * i].xyz;
    d = rays[2 * i + 1].xyz;
    size = ivec3(pc.dims) * 8;
    sgn = ivec3(sign(d));
    hits[i] = vec4(-1.0);
    float t = 0.0;
    for (int a = 0; a < 3; a++) {
        if (sgn[a] == 0) {
            if (!(o[a] >= 0.0 && o[a] < float(size[a]))) return;
        } else {
            t = max(t, plane_time(a, sgn[a] > 0 ? 0.0 : float(size[a])));
        }
    }
    if (isinf(t) || isnan(t)) return;
    ivec3 cell;
    for (int a = 0; a < 3; a++) cell[a] = cell_at(a, t, false);
    int budget = 3 * (size.x + size.y + size.z + 8);
    for (int step = 0; step < budget; step++) {
        bool leaving = false;
        bool inside = true;
        for (int a = 0; a < 3; a++) {
            leaving = leaving || (sgn[a] > 0 && cell[a] >= size[a]) || (sgn[a] < 0 && cell[a] < 0);
            inside = inside && cell[a] >= 0 && cell[a] < size[a];
        }
        if (leaving) return;
        int block = 1;
        if (inside) {
            if (!coarse_occupied(cell >> 5)) block = 32;
            else if (cell_word(cell >> 3) == EMPTY) block = 8;
            else if (solid(cell)) { hits[i] = vec4(vec3(cell), t); return; }
        }
        // Next event: the nearest block boundary along the ray.
        ivec3 bound;
        vec3 times = vec3(1.0 / 0.0);
        float t_next = 1.0 / 0.0;
        for (int a = 0; a < 3; a++) {
            if (sgn[a] == 0) continue;
            int base = (cell[a] >= 0 ? cell[a] / block : (cell[a] - block + 1) / block) * block;
            bound[a] = sgn[a] > 0 ? base + block : base;
            times[a] = plane_time(a, float(bound[a]));
            t_next = min(t_next, times[a]);
        }
        if (isinf(t_next)) return;
        bool positive_tie = false;
        for (int a = 0; a < 3; a++) positive_tie = positive_tie || (sgn[a] > 0 && times[a] == t_next);
        bvec3 stepped = bvec3(false);
        for (int a = 0; a < 3; a++) {
            if (sgn[a] != 0 && times[a] == t_next && (sgn[a] > 0) == positive_tie) {
                stepped[a] = true;
                cell[a] = sgn[a] > 0 ? bound[a] : bound[a] - 1;
            }
        }
        if (block > 1) {
            for (int a = 0; a < 3; a++) {
                if (!stepped[a] && sgn[a] != 0) cell[a] = cell_at(a, t_next, !positive_tie);
            }
        }
        t = t_next;
    }
}

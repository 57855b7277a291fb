// The path tracer: docs/DESIGN.md's light transport, a line-by-line port of
// render/src/cpu/mod.rs (CpuScene::radiance) in f32. Keep in sync with it and with
// render/src/vulkan/trace.rs (TraceParams).
#version 450
#extension GL_KHR_shader_subgroup_ballot : require
#extension GL_KHR_shader_subgroup_vote : require
// The sliced module (render/build.rs defines SAMPLE_SLICES): a pixel's samples of a dispatch
// are split among gl_NumWorkGroups.z invocations (slice = workgroup z), which add their sums
// to the accumulation with float atomics (the host zeroes it first when starting). Small
// images fill the GPU this way.
#ifdef SAMPLE_SLICES
#extension GL_EXT_shader_atomic_float : require
#endif
layout(local_size_x = 8, local_size_y = 8) in;

// Pipeline variants (render/src/vulkan/trace.rs `Variant`): what the scene needs. Code for
// a material kind, the sun or the gradient sky that a scene lacks is compiled out; the path
// length is a constant so short paths unroll. Sun and sky are also checked at run time, so
// the everything variant (the defaults) renders any scene.
layout(constant_id = 0) const bool HAS_LAMBERTIAN = true;
layout(constant_id = 1) const bool HAS_METAL = true;
layout(constant_id = 2) const bool HAS_DIELECTRIC = true;
layout(constant_id = 3) const bool HAS_EMISSIVE = true;
layout(constant_id = 4) const bool SUN = true;
layout(constant_id = 5) const bool GRADIENT_SKY = true;
layout(constant_id = 6) const uint MAX_BOUNCES = 4u;
layout(constant_id = 7) const bool COUNT_RAYS = false;
// Benchmark experiments (bench-gpu --experiment), 0 in every real render: bit 0 ends paths
// at the first hit (primary rays only), bit 1 decodes colours without pow, bit 2 counts
// every shadow ray as unblocked without tracing it, bit 3 skips light sampling (NEE), bit 4
// makes shaders/shadow.comp skip its work, bit 5 pads each traversal step with 64 multiply-adds
// (brickmap.glsl PAD_STEPS), bit 6 starts a subgroup's next samples together,
// bits 7..10 turn traversal skips off (brickmap.glsl SKIPS_OFF), bit 11 chooses light faces by
// weight alone (lights.glsl LIGHTS_BY_WEIGHT), bit 12 makes the sun-or-faces choice once for
// the subgroup's lanes at a vertex (LIGHTS_COHERENT), bit 13 starts camera rays at the camera
// (TILE_MARCH_OFF), bit 14 lowers the sun's and the faces' least share to 0.02 (sun_share),
// bit 15 adds a load each traversal step waits for (PAD_LOAD), bits 16..17
// descend the light tree 2 (value 1) or 1 (value 2: the binary descent) levels a step
// instead of 3 (lights.glsl LIGHT_LEVELS), bit 18 turns the light visibility cache on
// (lights.glsl LIGHT_CACHE_ON; render/src/vulkan/trace/light_cache.rs says why not by default).
layout(constant_id = 8) const uint EXPERIMENT = 0u;
// Shadow rays go to a queue that shaders/shadow.comp traces next, one per invocation, instead
// of being traced here: in a warp only some lanes have a shadow ray at a vertex, and tracing
// them here costs the whole warp a traversal (measured on the H100: shadow rays cost 4× what
// a camera ray costs when traced in place). When the queue is full they are traced here.
layout(constant_id = 9) const bool SHADOW_QUEUE = false;
// Next-event estimation of emissive voxels (shaders/lights.glsl): the scene has light faces
// and light sampling is on. Without it emissive voxels are found by BSDF rays only.
layout(constant_id = 10) const bool LIGHTS = false;
// The numbers paths are made from: independent (a hash chain) or Owen-scrambled Sobol
// points, padded in pairs of dimensions (Sequence::Sobol).
layout(constant_id = 11) const bool SOBOL = false;
// The editor's "dim the other objects": a path whose camera ray hits a voxel outside the box
// [p.dim_lo, p.dim_hi) carries the weight p.dim_lo.w (a display aid, never in a reference
// render: the CPU reference has no such weight). The sky and the sun are not dimmed.
layout(constant_id = 12) const bool DIM = false;
// The editor's ground grid: camera rays that reach the plane y = 0 before any voxel, within
// p.ground.y voxels of the world's x-z extent, and land within p.ground.z pixels of a line every
// p.ground.x voxels see the line's radiance p.ground.w (a display aid like DIM).
layout(constant_id = 13) const bool GRID = false;
// Coverage (a finished render's alpha): a camera ray adds 1 when it hits a voxel and 0 when
// it does not (the sun, the sky and the grid are not voxels), and the path ends there.
layout(constant_id = 14) const bool COVERAGE = false;
// A transparent background (a finished render with alpha): camera rays that reach the sky or
// the sun disc add nothing (the picture's colour is premultiplied by its coverage); the sky
// and the sun still light the voxels.
layout(constant_id = 15) const bool TRANSPARENT = false;

// Without dielectrics every ray travels in air: the traversal drops its medium branch.
#define MEDIUM_POSSIBLE HAS_DIELECTRIC
#define COUNT_STEPS COUNT_RAYS
#define SKIPS_OFF ((EXPERIMENT >> 7) & 15u)
#define PAD_STEPS ((EXPERIMENT & 32u) != 0u)
#define PAD_LOAD ((EXPERIMENT & 32768u) != 0u)
#define LIGHTS_BY_WEIGHT ((EXPERIMENT & 2048u) != 0u)
#define LIGHTS_COHERENT ((EXPERIMENT & 4096u) != 0u)
#define LIGHT_LEVELS max(3u - ((EXPERIMENT >> 16) & 3u), 1u)
// Used only where LIGHTS holds (an && of two spec-constant tests is miscompiled, below).
#define LIGHT_CACHE_ON ((EXPERIMENT & 262144u) != 0u)
// Camera rays start where their tile's frustum first meets an occupied coarse cell (off with
// experiment bit 13, and with the coarse grid's skip off: bit 7).
// (8320 = bits 13 and 7; one mask test: glslang miscompiles a && of two spec-constant tests.)
#define TILE_MARCH_OFF ((EXPERIMENT & 8320u) != 0u)
#include "brickmap.glsl"
#include "scene.glsl"
// Per pixel: the sum of its samples' radiance (rgb) and their count (a).
layout(std430, set = 0, binding = 6) buffer Accum { vec4 accum[]; };
// COUNT_RAYS variants only: camera rays, continuation rays, shadow rays, the traversal
// steps each kind took, then the most steps one camera or continuation ray took and one
// shadow ray took, then the iteration caps hit (brickmap.glsl's g_capped), then this pass's
// traversal steps and, per traversal of a subgroup, its slowest lane's steps times the
// subgroup's size (the lane steps the subgroup paid for: their ratio is the busy share).
layout(std430, set = 0, binding = 7) buffer Counters { uint counters[11]; };
#include "shadow_queue.glsl"
#include "lights.glsl"
uint g_rays[6];
uint g_most;        // COUNT_RAYS: the most steps one camera or continuation ray took, one shadow ray
uint g_most_shadow;
uint g_taken;       // COUNT_RAYS: lane steps this lane took, and (as the subgroup's elected lane)
uint g_paid;        // the lane steps its subgroup paid for

uint rng;
uint hash(uint x) {
    x = x * 747796405u + 2891336453u;
    x = ((x >> ((x >> 28u) + 4u)) ^ x) * 277803737u;
    return (x >> 22u) ^ x;
}
// Sobol: the sample's index in the pixel's sequence and the next dimension.
uint sob_index;
uint sob_dim;

// Burley 2020, "Practical Hash-based Owen Scrambling": a hash whose output bit j depends only
// on input bits ≤ j (Laine and Karras), applied to the bit-reversed value, is a nested
// uniform (Owen) scramble. Of an index below 2^k it stays in one aligned block of 2^k.
uint owen_scramble(uint x, uint seed) {
    x = bitfieldReverse(x);
    x += seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return bitfieldReverse(x);
}

// The second Sobol dimension (primitive polynomial x + 1: direction numbers v_1 = 1/2,
// v_k = v_{k-1} ^ (v_{k-1} >> 1)); the first is the bit-reversed index. Its generator matrix
// is Pascal's triangle mod 2: bit j (from the top) of the point is the coefficient of x^j in
// i(x + 1), where i(x) has the index's bits as coefficients. The Taylor shift by 1 over GF(2)
// takes five steps: within blocks of 2, 4 … 32 coefficients, the low half ^= the high half
// (the 32-step loop over direction numbers cost 5–14 % of a frame on the H200).
uint sobol_1(uint i) {
    i ^= (i >> 1) & 0x55555555u;
    i ^= (i >> 2) & 0x33333333u;
    i ^= (i >> 4) & 0x0f0f0f0fu;
    i ^= (i >> 8) & 0x00ff00ffu;
    i ^= (i >> 16) & 0x0000ffffu;
    return bitfieldReverse(i);
}

// Where the next numbers come from: dimension d of the sample's point (no-op for
// independent numbers). Each vertex has its own dimensions (vertex_dims), so a pair of them
// samples the same decision in every sample of the pixel.
void dims(uint d) {
    sob_dim = d;
}
uint vertex_dims(uint vertex) {
    return 2u + 8u * (vertex - 1u);
}

float rand() {
    if (!SOBOL) {
        rng = hash(rng);
        return float(rng >> 8) * (1.0 / 16777216.0);
    }
    uint d = sob_dim++;
    uint pair = d >> 1;
    // Each pair of dimensions has its own shuffle of the pixel's samples and its own
    // scrambles: pairs are independent of each other, each pair's points a scrambled
    // (0, 2)-sequence. Nothing is cached but the index and the dimension (the pixel's seed is
    // made again, only the coordinate asked for is scrambled): caching the seed and the
    // pair's two numbers kept 16 more registers live through the traversal (96 against 80)
    // and cost 5–6 % at complexities 2 and 3 on the H100.
    uint seed = hash(p.seed.x ^ hash(picture_index(gl_GlobalInvocationID.xy) * 9781u + 0x2545f491u));
    uint s = hash(seed ^ hash(pair * 0x9e3779b9u + 0x7f4a7c15u));
    uint i = owen_scramble(sob_index, s);
    uint v = (d & 1u) == 0u ? owen_scramble(bitfieldReverse(i), hash(s ^ 0xa511e9b3u))
                            : owen_scramble(sobol_1(i), hash(s ^ 0x63d83595u));
    return float(v >> 8) * (1.0 / 16777216.0);
}

vec3 sky(vec3 d) {
    if (!GRADIENT_SKY || p.sky_zenith.w == 0.0) return p.sky_horizon.rgb;
    float t = clamp(d.y, 0.0, 1.0);
    return p.sky_horizon.rgb * (1.0 - t) + p.sky_zenith.rgb * t;
}

float sun_area() { return PI * p.sun_centre.w * p.sun_centre.w; }

// Distance to the sun disc's front face along a unit ray, or -1; also its cosine.
float sun_hit(vec3 o, vec3 d, out float cos_l) {
    cos_l = 0.0;
    if (!SUN || p.sun_normal.w == 0.0) return -1.0;
    float denom = dot(d, p.sun_normal.xyz);
    if (denom >= 0.0) return -1.0;
    float t = dot(p.sun_centre.xyz - o, p.sun_normal.xyz) / denom;
    vec3 q = o + d * t - p.sun_centre.xyz;
    if (!(t > 0.0) || dot(q, q) > p.sun_centre.w * p.sun_centre.w) return -1.0;
    cos_l = -denom;
    return t;
}

float power_heuristic(float a, float b) {
    float s = a * a + b * b;
    return s > 0.0 ? a * a / s : 0.0;
}

float ggx_d(vec3 h, float alpha) {
    float a2 = alpha * alpha;
    float t = (h.x * h.x + h.y * h.y) / a2 + h.z * h.z;
    return 1.0 / (PI * a2 * t * t);
}

float ggx_lambda(vec3 w, float alpha) {
    float tan2 = (w.x * w.x + w.y * w.y) / (w.z * w.z);
    return (sqrt(1.0 + alpha * alpha * tan2) - 1.0) * 0.5;
}

vec3 ggx_sample_visible(vec3 wo, float alpha, float u1, float u2) {
    vec3 vh = normalize(vec3(alpha * wo.x, alpha * wo.y, wo.z));
    float lensq = vh.x * vh.x + vh.y * vh.y;
    vec3 t1 = lensq > 0.0 ? vec3(-vh.y, vh.x, 0.0) / sqrt(lensq) : vec3(1.0, 0.0, 0.0);
    vec3 t2 = cross(vh, t1);
    float r = sqrt(u1);
    float phi = 2.0 * PI * u2;
    float p1 = r * cos(phi);
    float s = 0.5 * (1.0 + vh.z);
    float p2 = (1.0 - s) * sqrt(max(0.0, 1.0 - p1 * p1)) + s * r * sin(phi);
    vec3 nh = t1 * p1 + t2 * p2 + vh * sqrt(max(0.0, 1.0 - p1 * p1 - p2 * p2));
    return normalize(vec3(alpha * nh.x, alpha * nh.y, max(0.0, nh.z)));
}

// Frame around an axis-aligned normal: z = n.
void frame(vec3 n, out vec3 t, out vec3 b) {
    t = n.x != 0.0 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0);
    b = cross(n, t);
}

// BSDF value and the pdf the sampler would have chosen wi with.
vec3 eval_bsdf(Shading s, vec3 wo, vec3 wi, out float pdf) {
    pdf = 0.0;
    if (wo.z <= 0.0 || wi.z <= 0.0) return vec3(0.0);
    if (HAS_LAMBERTIAN && s.kind == LAMBERTIAN) {
        pdf = wi.z / PI;
        return s.albedo / PI;
    }
    if (HAS_METAL && s.kind == METAL && s.param > 0.0) {
        float alpha = s.param * s.param;
        vec3 h = normalize(wo + wi);
        float d = ggx_d(h, alpha);
        float g2 = 1.0 / (1.0 + ggx_lambda(wo, alpha) + ggx_lambda(wi, alpha));
        float g1 = 1.0 / (1.0 + ggx_lambda(wo, alpha));
        pdf = g1 * d / (4.0 * wo.z);
        return s.albedo * (d * g2 / (4.0 * wo.z * wi.z));
    }
    return vec3(0.0);
}

// Samples wi: returns false when the path ends; weight = f·cos/pdf; pdf < 0 for delta lobes.
bool sample_bsdf(Shading s, vec3 wo, out vec3 wi, out vec3 weight, out float pdf) {
    weight = vec3(0.0);
    pdf = -1.0;
    wi = vec3(0.0, 0.0, 1.0);
    if (HAS_LAMBERTIAN && s.kind == LAMBERTIAN) {
        float u1 = rand();
        float r = sqrt(u1);
        float phi = 2.0 * PI * rand();
        wi = vec3(r * cos(phi), r * sin(phi), sqrt(max(0.0, 1.0 - u1)));
        weight = s.albedo;
        pdf = wi.z / PI;
        return wi.z > 0.0;
    }
    if (HAS_METAL && s.kind == METAL && s.param <= 0.0) {
        wi = vec3(-wo.x, -wo.y, wo.z);
        weight = s.albedo;
        return true;
    }
    if (HAS_METAL && s.kind == METAL) {
        float alpha = s.param * s.param;
        if (wo.z <= 0.0) return false;
        vec3 h = ggx_sample_visible(wo, alpha, rand(), rand());
        wi = h * (2.0 * dot(wo, h)) - wo;
        if (wi.z <= 0.0) return false;
        float lo = ggx_lambda(wo, alpha);
        weight = s.albedo * ((1.0 + lo) / (1.0 + lo + ggx_lambda(wi, alpha)));
        pdf = ggx_d(h, alpha) / (4.0 * wo.z * (1.0 + lo));
        return true;
    }
    return false;
}

// The path of this invocation's current sample. Paths are traced by one loop with a single
// traversal call (main): a vertex's shadow ray towards the sun is the loop's next ray, the
// path's continuation the one after, and a finished path starts the pixel's next sample in
// the same loop. So the traversal is compiled once (fewer registers than three inlined
// copies), and lanes of a warp tracing shadow rays, continuations and new camera rays run
// the traversal together instead of in turn.
vec3 pixel_sum;     // radiance of the pixel's samples so far (paths add to it directly)
vec3 path_beta;     // throughput
vec3 path_o;        // the next ray: origin, direction, first cell (not from the camera)
vec3 path_d;
ivec3 path_start;
int path_medium;    // material the path is inside (AIR outside dielectrics)
float path_pdf;     // pdf the BSDF chose path_d with; < 0: delta or camera
bool path_camera;   // the next ray is the camera ray
float path_t_min;   // where the camera ray's walk may start (no voxel lies before it)
float path_dim;     // DIM: the weight the camera hit gave the path
uint path_vertex;   // index of the vertex the next ray finds (1: the camera ray's hit)
// LIGHTS: what the vertex path_d left sampled (MIS on a hit of the sun or a light face): the
// probabilities it chose the sun and the light faces with, and its normal (path_o its point).
float path_sun_share;
float path_face_share;
ivec3 path_n;
// A pending shadow ray from path_o, starting in path_start: when nothing blocks it before
// shadow_t (except in the voxel of the light face in slot shadow_slot; NO_LIGHT for the
// sun), shadow_l counts. A vertex makes at most one (the sun's or a light face's).
bool shadow_pending;
vec3 shadow_d;
float shadow_t;
vec3 shadow_l;
uint shadow_slot;
// The light visibility cache entry the pending shadow ray counts in (NO_ENTRY: none), and the
// entry of the vertex being scattered (lights.glsl cache_entry).
uint shadow_entry;
uint vertex_entry;

void add_shadow(vec3 d, float t, vec3 l, uint light_slot) {
    shadow_pending = true;
    shadow_d = d;
    shadow_t = t;
    shadow_l = l;
    shadow_slot = light_slot;
    shadow_entry = vertex_entry;
}

// cos(max(0, θ − β)) for cos θ = c and sin β = sin_b (render/src/cpu/direct.rs `widened`).
float widened(float c, float sin_b) {
    float cos_b = sqrt(max(1.0 - sin_b * sin_b, 0.0));
    if (c >= cos_b) return 1.0;
    return c * cos_b + sqrt(max(1.0 - c * c, 0.0)) * sin_b;
}

// What the sun disc may give point pt with normal n (SunDisc::estimate): 0 exactly when no
// point of it can light pt.
float sun_estimate(vec3 pt, ivec3 n) {
    vec3 to = p.sun_centre.xyz - pt;
    float d2 = dot(to, to);
    float d = sqrt(d2);
    if (d <= p.sun_centre.w) return 0.0;
    vec3 w = to / d;
    float sin_b = p.sun_centre.w / d;
    float cr = widened(dot(w, vec3(n)), sin_b);
    float cl = widened(-dot(w, p.sun_normal.xyz), sin_b);
    if (!(cr > 0.0 && cl > 0.0)) return 0.0;
    vec3 l = p.sun_radiance.rgb;
    return (l.r + l.g + l.b) * sun_area() * cl * cr / d2;
}

// The sun's share of a vertex's light sample (direct.rs `sun_share`, LEAST_SHARE 0.1).
float sun_share(float sun, float faces) {
    if (!(faces > 0.0)) return 1.0;
    if (!(sun > 0.0)) return 0.0;
    if (LIGHTS_BY_WEIGHT) return 0.5;
    // Experiment bit 14: a least share of 0.02 instead (fewer face samples where the sun's
    // estimate dominates).
    float least = (EXPERIMENT & 16384u) != 0u ? 0.02 : 0.1;
    return least + (1.0 - 2.0 * least) * sun / (sun + faces);
}

// The depth (along the camera's forward axis, in units of its unnormalized film directions)
// before which no ray of this workgroup's tile meets an occupied coarse cell: the subgroup's
// lanes test consecutive slabs of the tile's frustum at once, each the box of its eight
// corners (a film direction is affine in the film position and a point linear in the depth,
// so the box holds every ray of the tile within the slab), widened by a voxel. Perspective
// cameras only (0 otherwise). The same for every lane of the subgroup.
const float SLAB = 32.0;
const int SLAB_ROUNDS = 4;
const int SLAB_CELLS = 64; // coarse cells a lane tests at most (more: taken as occupied)

uint ballot_word(uvec4 m, uint w) { return w == 0u ? m.x : (w == 1u ? m.y : (w == 2u ? m.z : m.w)); }

// Set bits of `m` below lane `lane`.
uint bits_below(uvec4 m, uint lane) {
    uint c = 0u;
    for (uint w = 0u; w < 4u; w++) {
        uint lo = 32u * w;
        if (lane >= lo + 32u) c += uint(bitCount(ballot_word(m, w)));
        else if (lane > lo) c += uint(bitCount(ballot_word(m, w) & ((1u << (lane - lo)) - 1u)));
    }
    return c;
}

float tile_start() {
    if (TILE_MARCH_OFF || p.cam_pos.w > 0.5) return 0.0;
    vec2 f0 = vec2(picture_pixel(gl_WorkGroupID.xy * gl_WorkGroupSize.xy));
    vec2 f1 = f0 + vec2(gl_WorkGroupSize.xy);
    vec3 c0 = film_direction(f0);
    vec3 c1 = film_direction(vec2(f1.x, f0.y));
    vec3 c2 = film_direction(vec2(f0.x, f1.y));
    vec3 c3 = film_direction(f1);
    vec3 dlo = min(min(c0, c1), min(c2, c3));
    vec3 dhi = max(max(c0, c1), max(c2, c3));
    uvec4 lanes = subgroupBallot(true);
    uint n = subgroupBallotBitCount(lanes);
    uint rank = subgroupBallotExclusiveBitCount(lanes);
    ivec3 last = ivec3((g_dims + 3u) / 4u) - 1;
    vec3 size = vec3(g_dims * 8u);
    vec3 o = p.cam_pos.xyz;
    for (int round = 0; round < SLAB_ROUNDS; round++) {
        float s0 = float(uint(round) * n + rank) * SLAB;
        float s1 = s0 + SLAB;
        vec3 lo = clamp(o + min(s0 * dlo, s1 * dlo) - 1.0, vec3(-64.0), size + 64.0);
        vec3 hi = clamp(o + max(s0 * dhi, s1 * dhi) + 1.0, vec3(-64.0), size + 64.0);
        ivec3 a = max(ivec3(floor(lo)) >> 5, ivec3(0));
        ivec3 b = min(ivec3(floor(hi)) >> 5, last);
        bool occupied = false;
        if (all(lessThanEqual(a, b))) {
            ivec3 e = b - a + 1;
            if (e.x * e.y * e.z > SLAB_CELLS) {
                occupied = true;
            } else {
                for (int z = a.z; z <= b.z && !occupied; z++)
                    for (int y = a.y; y <= b.y && !occupied; y++)
                        for (int x = a.x; x <= b.x && !occupied; x++)
                            occupied = coarse_occupied(ivec3(x, y, z));
            }
        }
        uvec4 hit = subgroupBallot(occupied);
        if (subgroupAny(occupied)) {
            uint below = bits_below(lanes, subgroupBallotFindLSB(hit));
            return float(uint(round) * n + below) * SLAB;
        }
    }
    return float(uint(SLAB_ROUNDS) * n) * SLAB;
}
float g_tile_start;

void begin_path(uvec2 px, uint s) {
    uint index = picture_index(px);
    rng = hash(p.seed.x ^ hash(index * 9781u + (p.seed.z + s) * 6271u + 1u));
    sob_index = p.seed.z + s;
    dims(0u);
    float jx = rand();
    vec2 f = vec2(picture_pixel(px)) + vec2(jx, rand());
    camera_ray(f, path_o, path_d);
    // Where the walk may start: a voxel back from the tile's start depth on this ray.
    path_t_min = max(g_tile_start * length(film_direction(f)) - 1.0, 0.0);
    path_beta = vec3(1.0);
    path_start = ivec3(0);
    path_medium = HAS_DIELECTRIC ? camera_medium(path_o) : AIR;
    path_pdf = -1.0;
    path_camera = true;
    path_dim = 1.0;
    path_vertex = 1u;
    path_sun_share = 1.0;
    path_face_share = 0.0;
    path_n = ivec3(0);
    shadow_pending = false;
    shadow_entry = NO_ENTRY;
    vertex_entry = NO_ENTRY;
}

// What the path's ray found (a voxel at t_voxel, or nothing): adds what it sees, prepares
// the vertex's shadow ray (shadow_pending) and the next ray. Returns whether the path goes on.
bool scatter(bool hit, ivec3 voxel, ivec3 normal, float t_voxel) {
    const uint bounces = MAX_BOUNCES;
    vec3 o = path_o;
    vec3 d = path_d;
    if (COVERAGE) {
        pixel_sum += vec3(hit ? 1.0 : 0.0);
        return false;
    }
    if (!hit) t_voxel = 1.0 / 0.0;
    if (GRID && path_camera && d.y != 0.0) {
        float tg = -o.y / d.y;
        vec2 q = (o + d * tg).xz;
        vec2 extent = vec2(p.grid.xz) * 8.0 + p.ground.y;
        if (tg > 0.0 && tg < t_voxel && all(greaterThanEqual(q, vec2(-p.ground.y))) && all(lessThanEqual(q, extent))) {
            // Voxels a pixel spans there (as shaders/guides.comp finds a footprint).
            float pixel = 2.0 * length(p.cam_up.xyz) / float(p.window.w);
            float footprint = p.cam_pos.w > 0.5 ? pixel : pixel * tg;
            vec2 off = abs(fract(q / p.ground.x + 0.5) - 0.5) * p.ground.x;
            if (min(off.x, off.y) < 0.5 * p.ground.z * footprint) {
                pixel_sum += path_beta * p.ground.w;
                return false;
            }
        }
    }
    float cos_l;
    float t_sun = sun_hit(o, d, cos_l);
    if (t_sun > 0.0 && t_sun < t_voxel) {
        if (TRANSPARENT && path_camera) return false;
        float share = LIGHTS ? path_sun_share : 1.0;
        float w = path_pdf < 0.0 ? 1.0 : power_heuristic(path_pdf, share * t_sun * t_sun / (cos_l * sun_area()));
        pixel_sum += path_beta * p.sun_radiance.rgb * w;
        return false;
    }
    if (!hit) {
        if (TRANSPARENT && path_camera) return false;
        pixel_sum += path_beta * sky(d);
        return false;
    }
    if (DIM && path_camera && (any(lessThan(vec3(voxel), p.dim_lo.xyz)) || any(greaterThanEqual(vec3(voxel), p.dim_hi.xyz)))) {
        path_beta *= p.dim_lo.w;
        path_dim = p.dim_lo.w;
    }
    vec3 pt = o + d * t_voxel;
    vec3 n = vec3(normal);
    int here = material_at(voxel);
    Shading s;
    if (here >= 0) s = material(here);
    bool crossing = HAS_DIELECTRIC && ((here >= 0 && s.kind == DIELECTRIC) || (here < 0 && path_medium >= 0));
    if ((EXPERIMENT & 1u) != 0u) {
        pixel_sum += path_beta * (here >= 0 ? s.albedo : vec3(0.0));
        return false;
    }
    if (HAS_EMISSIVE && here >= 0 && s.kind == EMISSIVE) {
        // It reflects nothing. Full weight unless the last vertex sampled the light faces.
        float w = 1.0;
        if (LIGHTS && path_face_share > 0.0 && path_pdf >= 0.0) {
            uint slot = light_slot_of(voxel, face_of(normal));
            // The vertex that sampled: its shadow rays started in path_start too.
            float pdf_light = slot == NO_LIGHT ? 0.0
                : path_face_share * light_probability(slot, o, path_n, cache_entry(path_start)) * t_voxel * t_voxel / -dot(d, n);
            w = power_heuristic(path_pdf, pdf_light);
        }
        pixel_sum += path_beta * s.albedo * s.param * w;
        return false;
    }
    if (path_vertex == bounces + 1u) return false;
    ivec3 front = voxel + normal;
    path_o = pt;
    if (crossing) {
        int medium = path_medium;
        float eta_i = medium >= 0 ? material(medium).param : 1.0;
        float eta_t = here >= 0 ? s.param : 1.0;
        vec3 tint = here >= 0 ? s.albedo : material(medium).albedo;
        float cos_i = -dot(d, n);
        float eta = eta_i / eta_t;
        float cos_t;
        float f = fresnel(cos_i, eta_i, eta_t, cos_t);
        dims(vertex_dims(path_vertex) + 6u);
        if (rand() < f) {
            path_d = normalize(d + n * (2.0 * cos_i));
            path_start = front;
        } else {
            path_d = normalize(d * eta + n * (eta * cos_i - cos_t));
            path_start = voxel;
            path_beta *= tint * (eta * eta);
            path_medium = here;
        }
        path_pdf = -1.0;
        path_face_share = 0.0;
    } else {
        vec3 ft;
        vec3 fb;
        frame(n, ft, fb);
        vec3 wo = vec3(dot(-d, ft), dot(-d, fb), dot(-d, n));
        path_start = front; // the shadow ray's first cell too
        bool delta = HAS_METAL && s.kind == METAL && s.param <= 0.0;
        uint base = vertex_dims(path_vertex);
        // One light per vertex (render/src/cpu/direct.rs): with LIGHTS from a vertex in air,
        // the sun or the light faces by their estimated contributions (dimension base + 2,
        // rescaled for the tree's descent); else the sun.
        bool sun_on = SUN && p.sun_normal.w != 0.0;
        float share = sun_on ? 1.0 : 0.0;
        float u = 0.0;
        path_face_share = 0.0;
        vertex_entry = NO_ENTRY;
        if (LIGHTS && !delta && path_medium == AIR && light_total() > 0.0) {
            vertex_entry = cache_entry(front);
            float faces = light_importance(1u, pt, normal);
            // The estimates weighed by how often each reached its light from here (the cache).
            share = sun_on ? sun_share(sun_estimate(pt, normal) * cache_sun_factor(vertex_entry),
                                       faces * cache_faces_factor(vertex_entry)) : 0.0;
            path_face_share = faces > 0.0 ? 1.0 - share : 0.0;
            path_n = normal;
            dims(base + 2u);
            u = rand();
        }
        path_sun_share = share;
        float u_light = (u - share) / (1.0 - share);
        if (LIGHTS_COHERENT) {
            // One uniform for the sun-or-faces choice of the subgroup's lanes here (each lane's
            // is still uniform and independent of its path, so each lane's estimate stays
            // unbiased), so that lanes that choose alike run one branch; the faces' descent
            // takes the lane's own dimension whole.
            if (sun_on && path_face_share > 0.0) {
                u_light = u;
                uint h = subgroupBroadcastFirst(hash(rng ^ hash(path_vertex * 0x9e3779b9u + 0x632be5abu)));
                u = float(h >> 8) * (1.0 / 16777216.0);
            }
        }
        if ((EXPERIMENT & 8u) != 0u || delta) {
            path_face_share = 0.0;
        } else if (sun_on && u < share) {
            dims(base);
            float r = p.sun_centre.w * sqrt(rand());
            float phi = 2.0 * PI * rand();
            vec3 y = p.sun_centre.xyz + (p.sun_e1.xyz * cos(phi) + p.sun_e2.xyz * sin(phi)) * r;
            vec3 to = y - pt;
            float dist = length(to);
            vec3 w = to / dist;
            float cl = -dot(w, p.sun_normal.xyz);
            vec3 wi = vec3(dot(w, ft), dot(w, fb), dot(w, n));
            if (cl > 0.0 && wi.z > 0.0) {
                float pdf_bsdf;
                vec3 fv = eval_bsdf(s, wo, wi, pdf_bsdf);
                if (fv != vec3(0.0)) {
                    float pdf_light = share * dist * dist / (cl * sun_area());
                    vec3 l = path_beta * fv * wi.z * p.sun_radiance.rgb * power_heuristic(pdf_light, pdf_bsdf) / pdf_light;
                    if ((EXPERIMENT & 4u) != 0u) pixel_sum += l;
                    else add_shadow(w, dist, l, NO_LIGHT);
                }
            }
        } else if (LIGHTS && path_face_share > 0.0) {
            // A light face from the tree by importance, a point uniform on it.
            float prob;
            uint slot = sample_light(min(u_light, 0.99999994), pt, normal, vertex_entry, prob);
            if (slot != NO_LIGHT) {
                ivec3 lv;
                uint lf;
                int lm;
                light_face(slot, lv, lf, lm);
                dims(base + 4u);
                float u1 = rand();
                float u2 = rand();
                vec3 y = face_point(lv, lf, u1, u2);
                vec3 to = y - pt;
                float dist = length(to);
                vec3 w = to / dist;
                float cl = -dot(w, face_normal(lf));
                vec3 wi = vec3(dot(w, ft), dot(w, fb), dot(w, n));
                if (cl > 0.0 && wi.z > 0.0) {
                    float pdf_bsdf;
                    vec3 fv = eval_bsdf(s, wo, wi, pdf_bsdf);
                    if (fv != vec3(0.0)) {
                        Shading e = material(lm);
                        float pdf_light = path_face_share * prob * dist * dist / cl;
                        add_shadow(w, dist, path_beta * fv * wi.z * e.albedo * e.param * power_heuristic(pdf_light, pdf_bsdf) / pdf_light, slot);
                    }
                }
            }
        }
        vec3 wi;
        vec3 weight;
        float pdf;
        dims(base + 6u);
        if (!sample_bsdf(s, wo, wi, weight, pdf)) return false;
        path_beta *= weight;
        path_pdf = pdf;
        path_d = ft * wi.x + fb * wi.y + n * wi.z;
    }
    path_camera = false;
    if (path_vertex >= 4u) {
        // A dimmed path continues as the undimmed one would (the same samples, weighted).
        vec3 b = DIM ? path_beta / path_dim : path_beta;
        float q = clamp(max(b.r, max(b.g, b.b)), 0.05, 1.0);
        dims(vertex_dims(path_vertex) + 3u);
        if (rand() >= q) return false;
        path_beta /= q;
    }
    path_vertex++;
    return true;
}

void main() {
    uvec2 px = gl_GlobalInvocationID.xy;
    if (px.x >= p.image.x || px.y >= p.image.y) return;
    g_dims = p.grid.xyz;
    g_words_per_column = p.grid.w;
    uint index = px.y * p.image.x + px.x;
    for (int k = 0; k < 6; k++) g_rays[k] = 0u;
    g_most = 0u;
    g_most_shadow = 0u;
    g_taken = 0u;
    g_paid = 0u;
    g_capped = 0u;
    pixel_sum = vec3(0.0);
    g_tile_start = tile_start();
    uint next_sample = gl_WorkGroupID.z * p.image.z; // this slice's first sample
    uint end_sample = next_sample + p.image.z;
    bool more = p.image.z > 0u; // samples left (the current path's included)
    if (more) begin_path(px, next_sample++);
    bool path_alive = true; // false: the path ended (its shadow ray may still be pending)
    while (more) {
        // Idle: this path ended and the subgroup has not (only with experiment bit 6).
        bool idle = !path_alive && !shadow_pending;
        if (!idle) {
            bool shadow = shadow_pending;
            bool camera = path_camera && !shadow;
            uint kind = shadow ? 2u : (camera ? 0u : 1u);
            if (COUNT_RAYS) g_rays[kind]++;
            g_steps = 0u;
            ivec3 voxel;
            ivec3 normal;
            float t;
            bool hit = trace(path_o, shadow ? shadow_d : path_d, camera, path_t_min, path_start,
                             shadow ? AIR : path_medium, shadow ? shadow_t : 1.0 / 0.0, voxel, normal, t);
            if (COUNT_RAYS) {
                g_rays[kind + 3u] += g_steps;
                // The most steps one ray took: kept per invocation, one atomic at the end (an
                // atomic per ray on one address slowed counted renders down several times).
                if (shadow) g_most_shadow = max(g_most_shadow, g_steps);
                else g_most = max(g_most, g_steps);
                // The subgroup's most steps, bit by bit with votes (arithmetic subgroup
                // operations are not among the ones the renderer requires).
                uint most = 0u;
                for (int b = 15; b >= 0; b--) {
                    if (subgroupAny(g_steps >= (most | (1u << b)))) most |= 1u << b;
                }
                g_taken += g_steps;
                if (subgroupElect()) g_paid += most * gl_SubgroupSize;
            }
            if (shadow) {
                if (LIGHTS && hit && shadow_slot != NO_LIGHT) {
                    // A light face's shadow ray may end in its light's voxel.
                    ivec3 target;
                    uint face;
                    int material;
                    light_face(shadow_slot, target, face, material);
                    hit = voxel != target;
                }
                if (LIGHTS) cache_record(shadow_entry, shadow_slot, !hit);
                if (!hit) pixel_sum += shadow_l;
                shadow_pending = false;
            } else {
                path_alive = scatter(hit, voxel, normal, t);
            }
            if (SHADOW_QUEUE) {
                // The shadow ray made by this vertex goes to the queue; the subgroup reserves
                // its slots with one atomic. A ray that does not fit stays pending and is
                // traced here.
                bool want = shadow_pending;
                uvec4 ballot = subgroupBallot(want);
                uint n = subgroupBallotBitCount(ballot);
                if (n > 0u) {
                    uint base = 0u;
                    if (subgroupElect()) {
                        base = atomicAdd(queue_count, n);
                        atomicMax(queue_groups, (min(base + n, shadow_rays.length()) + 63u) / 64u);
                    }
                    base = subgroupBroadcastFirst(base);
                    uint slot = base + subgroupBallotExclusiveBitCount(ballot);
                    if (want && push_shadow_ray(slot, path_o, path_start, shadow_d, shadow_t, shadow_l, shadow_slot, index, LIGHTS && shadow_entry != NO_ENTRY)) {
                        shadow_pending = false;
                        if (COUNT_RAYS) g_rays[2]++;
                    }
                }
            }
        }
        bool ended = !path_alive && !shadow_pending;
        bool together = (EXPERIMENT & 64u) == 0u || subgroupAll(ended);
        if (ended && together) {
            more = next_sample < end_sample;
            if (more) {
                begin_path(px, next_sample++);
                path_alive = true;
            }
        }
    }
    vec4 mine = vec4(pixel_sum, float(p.image.z));
#ifdef SAMPLE_SLICES
    atomicAdd(accum[index].x, mine.x);
    atomicAdd(accum[index].y, mine.y);
    atomicAdd(accum[index].z, mine.z);
    atomicAdd(accum[index].w, mine.w);
#else
    accum[index] = p.seed.w != 0u ? accum[index] + mine : mine;
#endif
    if (COUNT_RAYS) {
        for (int k = 0; k < 6; k++) atomicAdd(counters[k], g_rays[k]);
        atomicMax(counters[6], g_most);
        if (g_most_shadow != 0u) atomicMax(counters[7], g_most_shadow);
        if (g_capped != 0u) atomicAdd(counters[8], g_capped);
        atomicAdd(counters[9], g_taken);
        if (g_paid != 0u) atomicAdd(counters[10], g_paid);
    }
}

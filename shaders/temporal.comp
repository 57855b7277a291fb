// Temporal reprojection for the denoised viewport (render/src/vulkan/temporal.rs): while the
// camera moves every frame restarts the accumulation with one batch; this pass carries the
// previous frames' radiance over to the pixels that see the same surface again (SVGF's
// temporal stage, Schied et al. 2017), so the filter that follows works on many frames'
// samples instead of one. Each pixel's first surface (shaders/guides.comp's `primary`: the
// centre ray's first hit point, mirrors and glass included, and 8 · kind + face) is projected
// into the previous frame's camera, and the four previous pixels around it (bilinear) are kept
// where their first surfaces have the same material kind and face, on the same plane, within
// two of the previous pixels' footprints of the point.
// Modes:
//   0 moving: history = the reprojected previous history blended with this frame's mean
//     (an average over at most max_len samples: each new batch weighs at least 1/max_len);
//   1 still: the camera stopped and the accumulation restarts; until it holds max_len
//     samples the display source mixes in the last moving history (weight fading linearly
//     to 0 at max_len samples), from then on it is the accumulation itself (unbiased).
// Output (both modes): rgb = mean × n, w = n, so readers take it as an accumulation. Mode 0
// also keeps, per pixel, the mean square of each sample's demodulated luminance and writes
// the denoiser's moments from it as if the history were that many batches of one sample
// (SVGF's temporal variance): the filter's luminance weight then follows the history's noise
// instead of the spatial variance of one frame.
#version 450
layout(local_size_x = 8, local_size_y = 8) in;

layout(std430, set = 0, binding = 0) readonly buffer Accum { vec4 accum[]; };       // rgb sum, count
layout(std430, set = 0, binding = 1) readonly buffer Primary { vec4 primary[]; };   // this frame's
layout(std430, set = 0, binding = 2) readonly buffer PrevPrimary { vec4 prev_primary[]; };
// Two planes of a vec4 per pixel: (radiance mean × n, n), then (mean square of the demodulated
// luminance, 0, 0, 0); the first plane is what the filter reads.
layout(std430, set = 0, binding = 3) readonly buffer PrevHistory { vec4 prev_history[]; };
layout(std430, set = 0, binding = 4) writeonly buffer History { vec4 history[]; };
layout(std430, set = 0, binding = 5) readonly buffer Guides { vec4 guides[]; };       // guides.comp
layout(std430, set = 0, binding = 6) writeonly buffer Moments { vec4 moments[]; };   // denoise.comp

// The previous frame's camera (scene.glsl's Params fields: position with w = 1 when
// orthographic, forward, right and up scaled by the half-extents), the sizes, the mode, flags
// (bit 0: a previous frame exists) and the longest history in samples.
layout(push_constant) uniform Push {
    vec4 cam_pos;
    vec4 cam_forward;
    vec4 cam_right;
    vec4 cam_up;
    uvec2 size;
    uvec2 prev_size;
    uint mode;
    uint flags;
    float max_len;
} pc;

// A previous sample is the same surface when it lies on the pixel's face plane (voxel faces
// lie on integer planes) within this many voxels or, where a pixel spans more than that, one
// footprint (the planes of the several voxels a pixel covers), and within a few footprints.
const float PLANE_TOLERANCE = 1e-2;
const float FOOTPRINTS = 2.0;

// Something was hit and it is not a light (emission has no noise).
bool lit(vec4 first) {
    return first.w >= 0.0 && int(first.w) / 8 != 3;
}

// The pixel position (fractional, pixels from the top left) of world point x in the previous
// camera, or false when it lies behind it.
bool project(vec3 x, out vec2 f) {
    vec3 v = x - pc.cam_pos.xyz;
    float rr = dot(pc.cam_right.xyz, pc.cam_right.xyz);
    float uu = dot(pc.cam_up.xyz, pc.cam_up.xyz);
    float u;
    float w;
    if (pc.cam_pos.w > 0.5) {
        u = dot(v, pc.cam_right.xyz) / rr;
        w = dot(v, pc.cam_up.xyz) / uu;
    } else {
        float z = dot(v, pc.cam_forward.xyz);
        if (!(z > 0.0)) return false;
        u = dot(v, pc.cam_right.xyz) / (rr * z);
        w = dot(v, pc.cam_up.xyz) / (uu * z);
    }
    f = vec2((u + 1.0) * 0.5 * float(pc.prev_size.x), (1.0 - w) * 0.5 * float(pc.prev_size.y));
    return true;
}

// The previous history at the first surface `first` (point, code): its mean, length and
// luminance mean square, from the valid bilinear taps; false when none is valid.
bool reproject(vec4 first, out vec3 mean, out float len, out float square) {
    mean = vec3(0.0);
    len = 0.0;
    square = 0.0;
    vec2 f;
    if ((pc.flags & 1u) == 0u || !project(first.xyz, f)) return false;
    vec2 base = floor(f - 0.5);
    vec2 t = f - 0.5 - base;
    uint face = uint(first.w) % 8u;
    uint axis = face / 2u;
    float plane = axis == 0u ? first.x : (axis == 1u ? first.y : first.z);
    // Voxels a previous pixel spans at the point (as guides.comp finds a footprint).
    float pixel = 2.0 * length(pc.cam_up.xyz) / float(pc.prev_size.y);
    float footprint = pc.cam_pos.w > 0.5 ? pixel : pixel * distance(first.xyz, pc.cam_pos.xyz);
    float reach = FOOTPRINTS * footprint + 0.05;
    float total = 0.0;
    vec3 sum = vec3(0.0);
    float lens = 0.0;
    float squares = 0.0;
    for (int k = 0; k < 4; k++) {
        ivec2 q = ivec2(base) + ivec2(k & 1, k >> 1);
        if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, ivec2(pc.prev_size)))) continue;
        uint j = uint(q.y) * pc.prev_size.x + uint(q.x);
        vec4 pf = prev_primary[j];
        // Where a pixel spans a voxel or more, the faces its centre ray meets vary from pixel
        // to pixel: the same material kind and nearness suffice there.
        bool coarse = footprint >= 1.0;
        if (coarse ? (int(pf.w) / 8 != int(first.w) / 8 || pf.w < 0.0) : pf.w != first.w) continue;
        float prev_plane = axis == 0u ? pf.x : (axis == 1u ? pf.y : pf.z);
        if ((!coarse && abs(prev_plane - plane) > PLANE_TOLERANCE) || distance(pf.xyz, first.xyz) > reach) continue;
        vec4 h = prev_history[j];
        if (!(h.w > 0.0)) continue;
        float wx = (k & 1) != 0 ? t.x : 1.0 - t.x;
        float wy = (k >> 1) != 0 ? t.y : 1.0 - t.y;
        float wk = wx * wy;
        total += wk;
        sum += wk * h.rgb / h.w;
        lens += wk * h.w;
        squares += wk * prev_history[pc.prev_size.x * pc.prev_size.y + j].x;
    }
    if (total < 1e-3) return false;
    mean = sum / total;
    len = lens / total;
    square = squares / total;
    return true;
}

float luminance(vec3 c) { return dot(c, vec3(0.2126, 0.7152, 0.0722)); }
// A channel with (almost) no albedo is filtered as radiance (shaders/denoise.comp).
vec3 safe_albedo(vec3 a) { return mix(a, vec3(1.0), lessThan(a, vec3(1e-3))); }

void main() {
    uvec2 px = gl_GlobalInvocationID.xy;
    if (px.x >= pc.size.x || px.y >= pc.size.y) return;
    uint i = px.y * pc.size.x + px.x;
    vec4 a = accum[i];
    vec4 first = primary[i];
    vec3 prev;
    float len;
    float square;
    bool found = lit(first) && a.w > 0.0 && reproject(first, prev, len, square);
    vec3 albedo = safe_albedo(guides[2u * i + 1u].rgb);
    float l = a.w > 0.0 ? luminance(a.rgb / (a.w * albedo)) : 0.0;
    uint plane = pc.size.x * pc.size.y;
    if (!found) {
        history[i] = a;
        if (pc.mode == 0u) history[plane + i] = vec4(l * l, 0.0, 0.0, 0.0);
        return;
    }
    if (pc.mode == 0u) {
        float n = min(len + a.w, pc.max_len);
        float weight = a.w / n;
        vec3 mean = prev + (a.rgb / a.w - prev) * weight;
        float sq = square + (l * l - square) * weight;
        history[i] = vec4(mean * n, n);
        history[plane + i] = vec4(sq, 0.0, 0.0, 0.0);
        // As n batches of one sample each: (luminance sum, count, Σ S²/k, batches).
        if (guides[2u * i].w >= 0.0) {
            float lm = luminance(mean / albedo);
            moments[i] = vec4(lm * n, n, sq * n, n / a.w);
        }
    } else {
        float h = len * max(0.0, 1.0 - a.w / pc.max_len);
        float n = h + a.w;
        history[i] = vec4(prev * h + a.rgb, n);
    }
}

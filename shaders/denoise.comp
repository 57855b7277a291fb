// The viewport's edge-aware denoiser (render/src/vulkan/denoise.rs): an à-trous wavelet
// filter (Dammertz et al. 2010) with SVGF's variance-guided luminance weight (Schied et al.
// 2017), on the accumulation's mean divided by the first hit's albedo, guided by that hit's
// plane, normal, material kind and albedo (shaders/guides.comp). Its luminance weight uses the
// variance of each pixel's mean, estimated from the accumulation's batches (each frame adds
// one), so the filter narrows as samples accumulate, and the last step gives way to the raw
// mean between pc.fade_from and pc.fade_to samples.
// Modes (one pass each, `pc.mode`):
//   0 moments: after a batch, the batch's luminance sum S and size k update the pixel's
//     moments (previous luminance sum, previous count, Σ S²/k, batches);
//   1 prepare: mean / albedo and the variance of the mean's luminance into `dst`;
//   2 filter: one à-trous step of 2^step pixels from `src` to `dst` (the last fades to the
//     raw mean with the sample count and remodulates: albedo × result, count 1, what the
//     display pass reads).
#version 450
layout(local_size_x = 8, local_size_y = 8) in;

layout(std430, set = 0, binding = 0) readonly buffer Accum { vec4 accum[]; };   // rgb sum, count
layout(std430, set = 0, binding = 1) readonly buffer Guides { vec4 guides[]; }; // guides.comp
layout(std430, set = 0, binding = 2) buffer Moments { vec4 moments[]; };
layout(std430, set = 0, binding = 3) readonly buffer Src { vec4 src[]; };        // rgb, variance
layout(std430, set = 0, binding = 4) writeonly buffer Dst { vec4 dst[]; };
// flags: bit 0 this batch restarted the accumulation (moments), bit 1 the last step.
// fade_from, fade_to: the sample counts between which the last step gives way to the raw mean
// (linear in log2 of the count; render/src/vulkan/denoise.rs `Fade`); fade_to 0: never (also
// when the source is a moving camera's temporal history, whose count is frames blended).
layout(push_constant) uniform Push { uvec2 size; uint mode; uint step; uint flags; float fade_from; float fade_to; } pc;

// Luminance edge-stopping: differences are measured in standard deviations of the mean
// (SVGF's σ_l = 4); albedo differences (L1, linear) stop at about SIGMA_ALBEDO.
const float SIGMA_LUMINANCE = 4.0;
const float SIGMA_ALBEDO = 0.25;
// Batches before the per-pixel variance is trusted; until then the 3 × 3 spatial variance.
const float MIN_BATCHES = 4.0;

float luminance(vec3 c) { return dot(c, vec3(0.2126, 0.7152, 0.0722)); }

uint index_of(ivec2 q) { return uint(q.y) * pc.size.x + uint(q.x); }
bool inside(ivec2 q) { return all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, ivec2(pc.size))); }

// A channel with (almost) no albedo is filtered as radiance.
vec3 safe_albedo(vec3 a) { return mix(a, vec3(1.0), lessThan(a, vec3(1e-3))); }

// Whether the pixel's guide may be filtered at all: something was hit, and it is not a light
// (emission has no noise).
bool filtered(uint i) {
    return guides[2u * i].w >= 0.0 && int(guides[2u * i + 1u].w) / 8 != 3;
}

vec3 demodulated(uint i) {
    vec4 a = accum[i];
    vec3 mean = a.w > 0.0 ? a.rgb / a.w : vec3(0.0);
    return mean / safe_albedo(guides[2u * i + 1u].rgb);
}

// Geometry and material weight of neighbour q for pixel p (0 across edges), pixels apart.
float edge_weight(uint p, uint q, float pixels) {
    vec4 gp = guides[2u * p];
    vec4 gq = guides[2u * q];
    vec4 mp = guides[2u * p + 1u];
    vec4 mq = guides[2u * q + 1u];
    if (gq.w < 0.0 || mp.w != mq.w) return 0.0; // other kind or face direction: an edge
    // Distance of q's hit from p's face plane, against what the pixels between them span.
    int face = int(mp.w) % 8;
    vec3 d = gq.xyz - gp.xyz;
    float off = abs(face < 2 ? d.x : (face < 4 ? d.y : d.z));
    float plane = exp(-off / max(0.1, gp.w * pixels));
    vec3 da = abs(mp.rgb - mq.rgb);
    float albedo = exp(-(da.r + da.g + da.b) / SIGMA_ALBEDO);
    return plane * albedo;
}

void moments_pass(uint i) {
    vec4 m = (pc.flags & 1u) != 0u ? vec4(0.0) : moments[i];
    vec4 a = accum[i];
    float l = luminance(a.w > 0.0 ? a.rgb / safe_albedo(guides[2u * i + 1u].rgb) : vec3(0.0));
    float k = a.w - m.y;
    if (k > 0.0) {
        float s = l - m.x;
        m = vec4(l, a.w, m.z + s * s / k, m.w + 1.0);
    }
    moments[i] = m;
}

void prepare(ivec2 px, uint i) {
    vec3 c = demodulated(i);
    if (!filtered(i)) {
        dst[i] = vec4(c, 0.0);
        return;
    }
    vec4 m = moments[i];
    float var;
    if (m.w >= MIN_BATCHES && m.y > 0.0) {
        // Between-batch sum of squares over (B − 1) estimates one sample's variance.
        float sigma2 = max(0.0, m.z - m.x * m.x / m.y) / (m.w - 1.0);
        var = sigma2 / m.y;
    } else {
        // Too few batches: the spatial variance of the means around the pixel.
        float s1 = 0.0;
        float s2 = 0.0;
        float n = 0.0;
        for (int y = -1; y <= 1; y++) {
            for (int x = -1; x <= 1; x++) {
                ivec2 q = px + ivec2(x, y);
                if (!inside(q)) continue;
                uint j = index_of(q);
                if (!filtered(j) || edge_weight(i, j, 1.0) < 0.5) continue;
                float l = luminance(demodulated(j));
                s1 += l;
                s2 += l * l;
                n += 1.0;
            }
        }
        var = n > 1.0 ? max(0.0, s2 / n - (s1 / n) * (s1 / n)) : 0.0;
    }
    dst[i] = vec4(c, var);
}

const float KERNEL[3] = float[3](3.0 / 8.0, 1.0 / 4.0, 1.0 / 16.0);

void filter_step(ivec2 px, uint i) {
    vec4 centre = src[i];
    bool last = (pc.flags & 2u) != 0u;
    vec3 albedo = safe_albedo(guides[2u * i + 1u].rgb);
    if (!filtered(i)) {
        dst[i] = last ? vec4(centre.rgb * albedo, 1.0) : centre;
        return;
    }
    // The variance, blurred 3 × 3 (SVGF): a single pixel's estimate is itself noisy.
    float var = 0.0;
    float vw = 0.0;
    for (int y = -1; y <= 1; y++) {
        for (int x = -1; x <= 1; x++) {
            ivec2 q = px + ivec2(x, y);
            if (!inside(q)) continue;
            float k = (x == 0 ? 0.5 : 0.25) * (y == 0 ? 0.5 : 0.25);
            var += k * src[index_of(q)].w;
            vw += k;
        }
    }
    float sigma = SIGMA_LUMINANCE * sqrt(var / vw) + 1e-6;
    float lp = luminance(centre.rgb);
    int h = 1 << pc.step;
    vec3 sum = vec3(0.0);
    float wsum = 0.0;
    float vsum = 0.0;
    for (int y = -2; y <= 2; y++) {
        for (int x = -2; x <= 2; x++) {
            ivec2 q = px + ivec2(x, y) * h;
            if (!inside(q)) continue;
            uint j = index_of(q);
            vec4 c = src[j];
            float w = KERNEL[abs(x)] * KERNEL[abs(y)];
            if (j != i) {
                w *= edge_weight(i, j, float(h) * length(vec2(x, y)));
                w *= exp(-abs(luminance(c.rgb) - lp) / sigma);
            }
            sum += w * c.rgb;
            wsum += w;
            vsum += w * w * c.w;
        }
    }
    vec3 result = sum / wsum;
    if (last) {
        // The raw mean's share: a converged viewport shows the unbiased image.
        float raw = pc.fade_to <= 0.0 ? 0.0
            : clamp(log2(max(accum[i].w, 1.0) / pc.fade_from) / log2(pc.fade_to / pc.fade_from), 0.0, 1.0);
        dst[i] = vec4(mix(result, demodulated(i), raw) * albedo, 1.0);
    } else {
        dst[i] = vec4(result, vsum / (wsum * wsum));
    }
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (!inside(px)) return;
    uint i = index_of(px);
    if (pc.mode == 0u) moments_pass(i);
    else if (pc.mode == 1u) prepare(px, i);
    else filter_step(px, i);
}

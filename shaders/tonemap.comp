// Display stage: HDR accumulation (sum, count) at the internal resolution → mean →
// bilinear upscale to the output resolution (in linear HDR) → exposure → ACES fitted →
// sRGB 8-bit. Keep in sync with render/src/image.rs (resized_bilinear, aces_fitted,
// encode_srgb) and render/src/vulkan/tonemap.rs.
#version 450
layout(local_size_x = 8, local_size_y = 8) in;

layout(std430, set = 0, binding = 0) readonly buffer Hdr { vec4 hdr[]; };    // rgb sum, count
layout(std430, set = 0, binding = 1) writeonly buffer Ldr { uint ldr[]; };   // RGBA8 packed
// bgra = 1 writes the bytes in B, G, R, A order (a B8G8R8A8 swapchain image is copied from it).
layout(push_constant) uniform Push { uvec2 src; uvec2 dst; float scale; uint bgra; } pc;

vec3 aces_fitted(vec3 c) {
    const mat3 INPUT = mat3(0.59719, 0.07600, 0.02840,
                            0.35458, 0.90834, 0.13383,
                            0.04823, 0.01566, 0.83777);
    const mat3 OUTPUT = mat3(1.60475, -0.10208, -0.00327,
                             -0.53108, 1.10813, -0.07276,
                             -0.07367, -0.00605, 1.07602);
    vec3 v = INPUT * c;
    vec3 fit = (v * (v + 0.0245786) - 0.000090537) / (v * (0.983729 * v + 0.432951) + 0.238081);
    return clamp(OUTPUT * fit, 0.0, 1.0);
}

uint encode_srgb(float x) {
    x = clamp(x, 0.0, 1.0);
    float s = x <= 0.0031308 ? 12.92 * x : 1.055 * pow(x, 1.0 / 2.4) - 0.055;
    return uint(s * 255.0 + 0.5);
}

vec3 texel(int x, int y) {
    x = clamp(x, 0, int(pc.src.x) - 1);
    y = clamp(y, 0, int(pc.src.y) - 1);
    vec4 v = hdr[uint(y) * pc.src.x + uint(x)];
    return v.a > 0.0 ? v.rgb / v.a : vec3(0.0);
}

void main() {
    uvec2 px = gl_GlobalInvocationID.xy;
    if (px.x >= pc.dst.x || px.y >= pc.dst.y) return;
    vec2 s = (vec2(px) + 0.5) * (vec2(pc.src) / vec2(pc.dst)) - 0.5;
    vec2 f0 = floor(s);
    vec2 f = s - f0;
    ivec2 i = ivec2(f0);
    vec3 c = mix(mix(texel(i.x, i.y), texel(i.x + 1, i.y), f.x),
                 mix(texel(i.x, i.y + 1), texel(i.x + 1, i.y + 1), f.x), f.y) * pc.scale;
    vec3 t = aces_fitted(c);
    uint r = encode_srgb(t.r), b = encode_srgb(t.b);
    if (pc.bgra != 0u) { uint x = r; r = b; b = x; }
    ldr[px.y * pc.dst.x + px.x] = r | (encode_srgb(t.g) << 8) | (b << 16) | (255u << 24);
}

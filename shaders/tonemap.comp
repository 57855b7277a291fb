// Display stage: linear HDR accumulation → exposure → ACES fitted → sRGB 8-bit.
// Keep in sync with render/src/image.rs (aces_fitted, encode_srgb) and render/src/vulkan/tonemap.rs.
#version 450
layout(local_size_x = 64) in;

layout(std430, set = 0, binding = 0) readonly buffer Hdr { float hdr[]; };   // RGB triples
layout(std430, set = 0, binding = 1) writeonly buffer Ldr { uint ldr[]; };   // RGBA8 packed
layout(push_constant) uniform Push { uint pixels; float scale; } pc;

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

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.pixels) return;
    vec3 c = vec3(hdr[3 * i], hdr[3 * i + 1], hdr[3 * i + 2]) * pc.scale;
    vec3 t = aces_fitted(c);
    ldr[i] = encode_srgb(t.r) | (encode_srgb(t.g) << 8) | (encode_srgb(t.b) << 16) | (255u << 24);
}

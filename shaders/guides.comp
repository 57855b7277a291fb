// The denoiser's guides (render/src/vulkan/denoise.rs): per pixel the first thing its centre
// ray meets, found by the path tracer's own traversal. Two vec4 per pixel: the hit point and
// the pixel's footprint there (voxels per pixel; −1: nothing is hit, the pixel is not
// filtered), then the material's linear albedo and a code (8 · kind + face, face 0..5 =
// −x, +x, −y, +y, −z, +z). Keep in sync with shaders/denoise.comp.
#version 450
layout(local_size_x = 8, local_size_y = 8) in;

const bool HAS_METAL = true;
const bool HAS_DIELECTRIC = true;
const bool HAS_EMISSIVE = true;
const uint EXPERIMENT = 0u;
#include "brickmap.glsl"
#include "scene.glsl"

layout(std430, set = 0, binding = 6) writeonly buffer Guides { vec4 guides[]; };

void main() {
    uvec2 px = gl_GlobalInvocationID.xy;
    if (px.x >= p.image.x || px.y >= p.image.y) return;
    g_dims = p.grid.xyz;
    g_words_per_column = p.grid.w;
    uint index = px.y * p.image.x + px.x;
    vec3 o;
    vec3 d;
    camera_ray(vec2(px) + 0.5, o, d);
    ivec3 voxel;
    ivec3 normal;
    float t;
    int medium = camera_medium(o);
    if (!trace(o, d, true, ivec3(0), medium, 1.0 / 0.0, voxel, normal, t)) {
        guides[2u * index] = vec4(0.0, 0.0, 0.0, -1.0);
        guides[2u * index + 1u] = vec4(1.0, 1.0, 1.0, 0.0);
        return;
    }
    // Voxels one pixel spans at the hit: the film's pixel height times the distance
    // (perspective; `cam_up` is scaled by tan(fov / 2)) or the view's (orthographic).
    float pixel = 2.0 * length(p.cam_up.xyz) / float(p.image.y);
    float footprint = p.cam_pos.w > 0.5 ? pixel : pixel * t;
    int here = material_at(voxel);
    // Inside a medium the first interaction may be leaving it into air: the medium's face.
    Shading s = material(here >= 0 ? here : max(medium, 0));
    int face = normal.x != 0 ? (normal.x > 0 ? 1 : 0) : (normal.y != 0 ? (normal.y > 0 ? 3 : 2) : (normal.z > 0 ? 5 : 4));
    guides[2u * index] = vec4(o + d * t, footprint);
    guides[2u * index + 1u] = vec4(s.albedo, float(8 * s.kind + face));
}

// The denoiser's guides (render/src/vulkan/denoise.rs): per pixel the first surface its centre
// ray meets that is not a mirror or smooth dielectric, found by the path tracer's own
// traversal (through at most DELTA_BOUNCES of those, its albedo tinted by them). Two vec4 per pixel: the hit point and
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
// The first surface the centre ray meets, mirror and glass included (what temporal
// reprojection follows, shaders/temporal.comp): its point and 8 · kind + face, w = −1 for none.
layout(std430, set = 0, binding = 7) writeonly buffer Primary { vec4 primary[]; };

// Mirror and smooth-dielectric interfaces followed before the guide's surface.
const int DELTA_BOUNCES = 4;

void main() {
    uvec2 px = gl_GlobalInvocationID.xy;
    if (px.x >= p.image.x || px.y >= p.image.y) return;
    g_dims = p.grid.xyz;
    g_words_per_column = p.grid.w;
    uint index = px.y * p.image.x + px.x;
    vec3 o;
    vec3 d;
    camera_ray(vec2(picture_pixel(px)) + 0.5, o, d);
    // Through mirrors and smooth dielectrics to the first surface that is neither (the way
    // its light most likely goes: refraction unless Fresnel reflects more, or total internal
    // reflection), so a reflection or what lies behind glass is filtered on its own plane.
    int medium = camera_medium(o);
    primary[index] = vec4(0.0, 0.0, 0.0, -1.0);
    vec3 tint = vec3(1.0);
    float travelled = 0.0;
    ivec3 start = ivec3(0);
    for (int bounce = 0; bounce <= DELTA_BOUNCES; bounce++) {
        ivec3 voxel;
        ivec3 normal;
        float t;
        if (!trace(o, d, bounce == 0, 0.0, start, medium, 1.0 / 0.0, voxel, normal, t)) break;
        travelled += t;
        vec3 n = vec3(normal);
        int here = material_at(voxel);
        // Inside a medium the first interaction may be leaving it into air: the medium's face.
        Shading s = material(here >= 0 ? here : max(medium, 0));
        int face = normal.x != 0 ? (normal.x > 0 ? 1 : 0) : (normal.y != 0 ? (normal.y > 0 ? 3 : 2) : (normal.z > 0 ? 5 : 4));
        if (bounce == 0) primary[index] = vec4(o + d * t, float(8 * s.kind + face));
        bool crossing = (here >= 0 && s.kind == DIELECTRIC) || (here < 0 && medium >= 0);
        bool mirror = here >= 0 && s.kind == METAL && s.param <= 0.0;
        if (bounce < DELTA_BOUNCES && (crossing || mirror)) {
            o += d * t;
            float cos_i = -dot(d, n);
            if (mirror) {
                tint *= s.albedo;
                d = normalize(d + n * (2.0 * cos_i));
                start = voxel + normal;
                continue;
            }
            float eta_i = medium >= 0 ? material(medium).param : 1.0;
            float eta_t = here >= 0 ? s.param : 1.0;
            float eta = eta_i / eta_t;
            float cos_t;
            float f = fresnel(cos_i, eta_i, eta_t, cos_t);
            if (f > 0.5) {
                d = normalize(d + n * (2.0 * cos_i));
                start = voxel + normal;
            } else {
                tint *= here >= 0 ? s.albedo : material(medium).albedo;
                d = normalize(d * eta + n * (eta * cos_i - cos_t));
                start = voxel;
                medium = here;
            }
            continue;
        }
        // Voxels one pixel spans at the hit: the film's pixel height times the distance
        // (perspective; `cam_up` is scaled by tan(fov / 2)) or the view's (orthographic).
        float pixel = 2.0 * length(p.cam_up.xyz) / float(p.window.w);
        float footprint = p.cam_pos.w > 0.5 ? pixel : pixel * travelled;
        guides[2u * index] = vec4(o + d * t, footprint);
        guides[2u * index + 1u] = vec4(tint * s.albedo, float(8 * s.kind + face));
        return;
    }
    // Nothing but the sky (perhaps in a mirror): not filtered.
    guides[2u * index] = vec4(0.0, 0.0, 0.0, -1.0);
    guides[2u * index + 1u] = vec4(1.0, 1.0, 1.0, 0.0);
}

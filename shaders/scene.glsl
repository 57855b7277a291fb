// The scene as every path-tracing shader reads it: the trace parameters (binding 5; keep in
// sync with render/src/vulkan/trace.rs TraceParams) and the material tables decoded. A shader
// that includes it defines HAS_METAL, HAS_DIELECTRIC, HAS_EMISSIVE and EXPERIMENT first, and
// includes brickmap.glsl (the tables' binding) before it.

struct Params {
    vec4 cam_pos;       // xyz
    vec4 cam_forward;   // xyz
    vec4 cam_right;     // xyz, scaled by tan(fov/2)·aspect
    vec4 cam_up;        // xyz, scaled by tan(fov/2)
    vec4 sun_centre;    // xyz, w: radius
    vec4 sun_normal;    // xyz, w: 1 when the sun is on
    vec4 sun_e1;
    vec4 sun_e2;
    vec4 sun_radiance;  // rgb
    vec4 sky_horizon;   // rgb
    vec4 sky_zenith;    // rgb, w: 1 for a gradient, 0 for uniform (horizon colour)
    uvec4 grid;         // bricks xyz, coarse words per column
    uvec4 image;        // width, height, samples per pixel and slice in this dispatch, B (the shader
                        // uses the variant's MAX_BOUNCES; B is kept for the image key)
    uvec4 seed;         // seed, camera medium (material + 1, 0 for air), first sample index,
                        // 1 to add to the accumulation (0 to start it)
    vec4 dim_lo;        // DIM variants: the undimmed box's low corner (voxels), w: the factor
    vec4 dim_hi;        // camera hits outside the box are weighted by; xyz: its high corner
    vec4 ground;        // GRID variants: line spacing (voxels), how far the grid reaches past the
                        // world's sides (voxels), the lines' width in pixels, their radiance
    uvec4 window;       // this image's place in the whole picture (a tile of a tiled render):
                        // its top left pixel x, y there, and the picture's width, height
};

layout(std430, set = 0, binding = 5) readonly buffer ParamBuffer { Params p; };

const float PI = 3.14159265358979;
const int LAMBERTIAN = 0;
const int METAL = 1;
const int DIELECTRIC = 2;
const int EMISSIVE = 3;

struct Shading { int kind; vec3 albedo; float param; };

float srgb_to_linear(uint c) {
    float x = float(c) / 255.0;
    if ((EXPERIMENT & 2u) != 0u) return x * x;
    return x <= 0.04045 ? x / 12.92 : pow((x + 0.055) / 1.055, 2.4);
}

Shading material(int index) {
    uint v = (tables.packed_materials[index / 2] >> (16 * (index % 2))) & 0xFFFFu;
    Shading s;
    s.kind = int(v & 3u);
    uint param = (v >> 2) & 63u;
    uint colour = tables.colours[v >> 8];
    s.albedo = vec3(srgb_to_linear(colour & 0xFFu), srgb_to_linear((colour >> 8) & 0xFFu), srgb_to_linear((colour >> 16) & 0xFFu));
    s.param = HAS_METAL && s.kind == METAL ? tables.roughness[param]
            : (HAS_DIELECTRIC && s.kind == DIELECTRIC ? tables.ior[param]
            : (HAS_EMISSIVE && s.kind == EMISSIVE ? tables.strength[param] : 0.0));
    return s;
}

// The dielectric a camera ray starts in (AIR outside them): the same for every ray of a
// perspective camera (found on the host), per ray for an orthographic one.
int camera_medium(vec3 o) {
    if (p.cam_pos.w < 0.5) return int(p.seed.y) - 1;
    ivec3 c = ivec3(floor(o));
    if (any(lessThan(c, ivec3(0))) || any(greaterThanEqual(c, ivec3(p.grid.xyz) * 8))) return AIR;
    int m = material_at(c);
    return (m >= 0 && material(m).kind == DIELECTRIC) ? m : AIR;
}

// A pixel's index in the whole picture (what its random numbers are made from, so a tile
// renders exactly the pixels the untiled picture has there).
uint picture_index(uvec2 px) {
    return (px.y + p.window.y) * p.window.z + px.x + p.window.x;
}

// A pixel of this image as a pixel of the whole picture.
uvec2 picture_pixel(uvec2 px) {
    return px + p.window.xy;
}

// Film position `f` (pixels from the picture's top left corner) as the camera's (u, v) in
// [−1, 1]², v up.
vec2 film_uv(vec2 f) {
    return vec2(2.0 * f.x / float(p.window.z) - 1.0, 1.0 - 2.0 * f.y / float(p.window.w));
}

// The perspective camera's unnormalized direction through film position `f` (affine in `f`).
vec3 film_direction(vec2 f) {
    vec2 uv = film_uv(f);
    return p.cam_forward.xyz + p.cam_right.xyz * uv.x + p.cam_up.xyz * uv.y;
}

// The camera ray through film position `f` (a pixel's samples jitter it within
// [x, x + 1) × [y, y + 1)).
void camera_ray(vec2 f, out vec3 o, out vec3 d) {
    if (p.cam_pos.w > 0.5) {
        // Orthographic: parallel rays from the image plane through the camera's position.
        vec2 uv = film_uv(f);
        o = p.cam_pos.xyz + p.cam_right.xyz * uv.x + p.cam_up.xyz * uv.y;
        d = p.cam_forward.xyz;
    } else {
        o = p.cam_pos.xyz;
        d = normalize(film_direction(f));
    }
}

// Unpolarized Fresnel reflectance of a smooth interface from index eta_i into eta_t at
// cos_i; 1 under total internal reflection. `cos_t`: the refracted ray's cosine (0 then).
float fresnel(float cos_i, float eta_i, float eta_t, out float cos_t) {
    float eta = eta_i / eta_t;
    float sin2_t = eta * eta * max(0.0, 1.0 - cos_i * cos_i);
    float f = 1.0;
    cos_t = 0.0;
    if (sin2_t < 1.0) {
        cos_t = sqrt(1.0 - sin2_t);
        float rs = (eta_i * cos_i - eta_t * cos_t) / (eta_i * cos_i + eta_t * cos_t);
        float rp = (eta_t * cos_i - eta_i * cos_t) / (eta_t * cos_i + eta_i * cos_t);
        f = 0.5 * (rs * rs + rp * rp);
    }
    return f;
}

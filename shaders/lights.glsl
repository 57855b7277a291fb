// The light faces of emissive voxels (brickmap/src/lights.rs: layout, weights, descent),
// binding 10. A face is chosen by descending the sum tree from the root, exactly as
// `Lights::sample` does on the CPU. Keep in sync with both.
layout(std430, set = 0, binding = 10) readonly buffer LightFaces { uint light_words[]; };

const uint LIGHT_WEIGHTS = 4u;  // 256 f32 material weights after the 4-word header
const uint LIGHT_NODES = 260u;  // 2C f32 nodes: root 1, children 2i and 2i + 1, leaves C..2C

float light_node(uint i) { return uintBitsToFloat(light_words[LIGHT_NODES + i]); }
float light_total() { return light_node(1u); }
float light_weight(int material) { return uintBitsToFloat(light_words[LIGHT_WEIGHTS + uint(material)]); }

// The slot holding u ∈ [0, 1) of the total weight (its probability is its leaf / total).
// Call only when the total is positive.
uint sample_light(float u) {
    uint c = light_words[0];
    float x = u * light_total();
    uint i = 1u;
    while (i < c) {
        float l = light_node(2u * i);
        float r = light_node(2u * i + 1u);
        if ((x < l && l > 0.0) || r <= 0.0) {
            i = 2u * i;
        } else {
            x -= l;
            i = 2u * i + 1u;
        }
    }
    return i - c;
}

// A slot's face: its voxel, which face (−x, +x, −y, +y, −z, +z) and the voxel's material.
void light_face(uint slot, out ivec3 voxel, out uint face, out int material) {
    uint at = LIGHT_NODES + 2u * light_words[0] + 2u * slot;
    uint w0 = light_words[at];
    uint w1 = light_words[at + 1u];
    voxel = ivec3(int(w0 & 0xFFFu), int(w1 & 0xFFFFu), int((w0 >> 12) & 0xFFFu));
    face = (w0 >> 24) & 7u;
    material = int(w1 >> 16);
}

vec3 face_normal(uint face) {
    vec3 n = vec3(0.0);
    n[face >> 1] = (face & 1u) != 0u ? 1.0 : -1.0;
    return n;
}

// The point (u1, u2) of a voxel's face (render/src/cpu/mod.rs `face_point`).
vec3 face_point(ivec3 voxel, uint face, float u1, float u2) {
    float high = float(face & 1u);
    uint axis = face >> 1;
    vec3 o = axis == 0u ? vec3(high, u1, u2) : (axis == 1u ? vec3(u1, high, u2) : vec3(u1, u2, high));
    return vec3(voxel) + o;
}

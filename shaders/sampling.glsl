// Direction sampling and the MIS weight.

const float PI = 3.14159265358979323846;
const float INV_PI = 0.31830988618379067154;

// Orthonormal basis around n (Duff et al. 2017, branchless).
void onb(vec3 n, out vec3 t, out vec3 b) {
    float s = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (s + n.z);
    float c = n.x * n.y * a;
    t = vec3(1.0 + s * n.x * n.x * a, s * c, -s * n.x);
    b = vec3(c, s + n.y * n.y * a, -n.y);
}

vec3 to_world(vec3 local, vec3 n) {
    vec3 t, b;
    onb(n, t, b);
    return local.x * t + local.y * b + local.z * n;
}

// Cosine-weighted hemisphere around n; pdf = cos(theta) / pi.
vec3 sample_cosine_hemisphere(vec2 u, vec3 n) {
    float r = sqrt(u.x);
    float phi = 2.0 * PI * u.y;
    return to_world(vec3(r * cos(phi), r * sin(phi), sqrt(max(0.0, 1.0 - u.x))), n);
}

// Uniform direction inside the cone of half-angle acos(cos_max) around axis; pdf = 1 / (2 pi (1 - cos_max)).
vec3 sample_cone(vec2 u, vec3 axis, float cos_max) {
    float cos_t = 1.0 - u.x * (1.0 - cos_max);
    float sin_t = sqrt(max(0.0, 1.0 - cos_t * cos_t));
    float phi = 2.0 * PI * u.y;
    return to_world(vec3(sin_t * cos(phi), sin_t * sin(phi), cos_t), axis);
}

vec3 sample_uniform_sphere(vec2 u) {
    float z = 1.0 - 2.0 * u.x;
    float r = sqrt(max(0.0, 1.0 - z * z));
    float phi = 2.0 * PI * u.y;
    return vec3(r * cos(phi), r * sin(phi), z);
}

// Uniform point on a triangle as barycentrics (b1, b2) of v1 and v2.
vec2 sample_triangle(vec2 u) {
    float s = sqrt(u.x);
    return vec2(1.0 - s, u.y * s);
}

// Veach's power heuristic (beta = 2) for the strategy with pdf `a` against one with pdf `b`.
float power_heuristic(float a, float b) {
    float a2 = a * a;
    float b2 = b * b;
    return a2 + b2 > 0.0 ? a2 / (a2 + b2) : 0.0;
}

float max3(vec3 v) { return max(v.x, max(v.y, v.z)); }

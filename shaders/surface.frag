#version 430 core
// Textured, lit surface for synthetic images: an albedo made of multi-scale procedural noise
// and/or photographs (tri-planar projection in world space), optional facade windows, and
// two-sided Lambertian shading. Everything is a function of the world position, so views
// agree on the texture of a surface point (what multi-view matching needs).
#include "noise.glsl"

in vec3 v_world;  // relative to u_origin

uniform vec3 u_origin;
uniform vec3 u_light_dir;  // unit, towards the light
uniform float u_ambient;   // share of light that does not depend on orientation
uniform vec3 u_up;         // world up (window rows run along it)
uniform uint u_seed;
uniform int u_num_photos;
uniform int u_octaves;
uniform sampler2DArray u_photos;

// Per face: xyz unit normal, w material index.
layout(std430, binding = 0) readonly buffer FaceData { vec4 face_data[]; };

// Per material, three vec4 (packed in gl/mesh_renderer.cc, SurfaceRenderer::Impl).
struct Material {
  vec4 color_contrast;  // rgb albedo, a: noise contrast (0 = flat colour)
  vec4 noise_photo;     // x: coarsest noise period, y: photo period, z: photo layer (-1 none),
                        // w: photo weight
  vec4 windows;         // x: window spacing along the facade (0 = none), y: floor height,
                        // z: window width share, w: window height share
};
layout(std430, binding = 1) readonly buffer Materials { Material materials[]; };

layout(location = 0) out vec4 o_color;

vec3 PhotoTriplanar(vec3 p, vec3 n, float period, int layer) {
  vec3 w = pow(abs(n), vec3(4.0));
  w /= (w.x + w.y + w.z);
  vec3 x = texture(u_photos, vec3(p.yz / period, float(layer))).rgb;
  vec3 y = texture(u_photos, vec3(p.xz / period, float(layer))).rgb;
  vec3 z = texture(u_photos, vec3(p.xy / period, float(layer))).rgb;
  return x * w.x + y * w.y + z * w.z;
}

void main() {
  vec4 face = face_data[gl_PrimitiveID];
  vec3 n = face.xyz;
  Material m = materials[int(face.w)];
  vec3 p = v_world + u_origin;

  float period = max(m.noise_photo.x, 1e-6);
  // fbm has a standard deviation of ~0.15; scale it to ~0.35 before applying the contrast. The
  // gain of 0.72 keeps the fine octaves strong enough for window-based matching.
  float detail = clamp(2.2 * ms_fbm(p / period, u_octaves, 0.72, u_seed), -1.0, 1.0);
  float hue = clamp(2.5 * ms_fbm(p / (period * 1.7) + vec3(17.0), 3, 0.5, u_seed + 1000u),
                    -1.0, 1.0);
  vec3 albedo = m.color_contrast.rgb *
                max(1.0 + m.color_contrast.a * (detail + vec3(0.2, 0.0, -0.2) * hue), 0.05);

  int layer = int(m.noise_photo.z);
  if (layer >= 0 && layer < u_num_photos) {
    vec3 photo = PhotoTriplanar(p, n, m.noise_photo.y, layer);
    albedo = mix(albedo, photo * (m.color_contrast.rgb / 0.6) * (1.0 + 0.3 * detail),
                 m.noise_photo.w);
  }

  // Facade windows: vertical faces only, laid out in the plane's (along, up) coordinates.
  if (m.windows.x > 0.0 && abs(dot(n, u_up)) < 0.3) {
    vec3 along_dir = normalize(cross(u_up, n));
    float along = dot(p, along_dir) / m.windows.x;
    float up = dot(p, u_up) / m.windows.y;
    vec2 cell = vec2(fract(along), fract(up));
    bool ground_floor = floor(up) < 1.0;
    if (!ground_floor && cell.x > 0.5 - 0.5 * m.windows.z && cell.x < 0.5 + 0.5 * m.windows.z &&
        cell.y > 0.3 && cell.y < 0.3 + m.windows.w) {
      float glass = 0.5 + 0.5 * ms_gradient_noise(vec3(floor(along), floor(up), 3.0), u_seed);
      albedo = vec3(0.12, 0.15, 0.2) * (0.6 + 0.8 * glass) + 0.1 * detail;
    }
  }

  float lambert = abs(dot(n, u_light_dir));
  vec3 color = albedo * (u_ambient + (1.0 - u_ambient) * lambert);
  o_color = vec4(clamp(color, 0.0, 1.0), 1.0);
}

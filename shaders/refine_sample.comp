#version 430 core
// Photometric gradient, first pass (docs/design/refine.md "The energy"): for every reference pixel
// that sees a face, the neighbour's image through the mesh (bilinear, with its exact
// derivatives), where the neighbour sees the point and the ray meets the face steeply enough.
// Writes the window's inputs m, mI, mJ, mI^2 / mJ^2, mIJ, dJ/dd, |d(neighbour pixel)/dd|^2 and
// the face where m = 1 (-1 elsewhere).
layout(local_size_x = 16, local_size_y = 8) in;

#include "refine_faces.glsl"

// Images rather than samplers: no filter state to get wrong on the integer face ids.
layout(binding = 3, r32i) readonly uniform iimage2D u_seen_face;    // reference: face, -1 none
layout(binding = 4, r32f) readonly uniform image2D u_shadow_depth;  // neighbour: camera z, 0 none
layout(binding = 5, r32f) readonly uniform image2D u_image_i;
layout(binding = 6, r32f) readonly uniform image2D u_image_j;

layout(binding = 0, rgba32f) writeonly uniform image2D o_window0;  // m, mI, mJ, mI^2
layout(binding = 1, rgba32f) writeonly uniform image2D o_window1;  // mJ^2, mIJ, dJ/dd, parallax^2
layout(binding = 2, r32i) writeonly uniform iimage2D o_face;

uniform ivec2 u_size_i;
uniform ivec2 u_size_j;
uniform mat3 u_r_j;       // world directions to the neighbour's camera frame
uniform vec3 u_centre_j;  // C (the reference's centre) in the neighbour's camera frame
uniform vec4 u_k_j;       // the neighbour's fx, fy, cx, cy
uniform float u_near_j;
uniform float u_min_cos;
uniform float u_max_depth_ratio;  // 1 + occlusion tolerance

void Skip(ivec2 p) {
  imageStore(o_window0, p, vec4(0.0));
  imageStore(o_window1, p, vec4(0.0));
  imageStore(o_face, p, ivec4(-1));
}

void main() {
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (p.x >= u_size_i.x || p.y >= u_size_i.y) return;
  int f = imageLoad(u_seen_face, p).x;
  if (f < 0) {
    Skip(p);
    return;
  }
  RefineFace face = u_faces[f];
  vec3 ray = PixelRay(p);
  float cos_incidence = dot(face.unit_offset.xyz, ray);
  if (abs(cos_incidence) < u_min_cos || cos_incidence == 0.0) {
    Skip(p);
    return;
  }
  float depth = face.unit_offset.w / cos_incidence;
  vec3 ray_j = u_r_j * ray;  // d(neighbour camera coordinates)/dd
  vec3 y = u_centre_j + depth * ray_j;
  if (y.z <= u_near_j) {
    Skip(p);
    return;
  }
  float u = u_k_j.x * y.x / y.z + u_k_j.z, v = u_k_j.y * y.y / y.z + u_k_j.w;
  float ax = u - 0.5, ay = v - 0.5;  // array coordinates of the sample
  if (!(ax >= 0.0 && ay >= 0.0 && ax <= float(u_size_j.x - 1) && ay <= float(u_size_j.y - 1))) {
    Skip(p);
    return;
  }
  ivec2 q = min(ivec2(int(u), int(v)), u_size_j - 1);
  float shadow = imageLoad(u_shadow_depth, q).x;
  if (shadow > 0.0 && y.z > u_max_depth_ratio * shadow) {  // hidden from j
    Skip(p);
    return;
  }

  ivec2 a = min(ivec2(int(ax), int(ay)), u_size_j - 2);
  float fx = ax - float(a.x), fy = ay - float(a.y);
  float i00 = imageLoad(u_image_j, a).x, i10 = imageLoad(u_image_j, a + ivec2(1, 0)).x;
  float i01 = imageLoad(u_image_j, a + ivec2(0, 1)).x;
  float i11 = imageLoad(u_image_j, a + ivec2(1, 1)).x;
  float j = (1.0 - fy) * ((1.0 - fx) * i00 + fx * i10) + fy * ((1.0 - fx) * i01 + fx * i11);
  float dx = (1.0 - fy) * (i10 - i00) + fy * (i11 - i01);
  float dy = (1.0 - fx) * (i01 - i00) + fx * (i11 - i10);
  float z2 = y.z * y.z;
  float du = u_k_j.x * (ray_j.x * y.z - y.x * ray_j.z) / z2;
  float dv = u_k_j.y * (ray_j.y * y.z - y.y * ray_j.z) / z2;
  float i = imageLoad(u_image_i, p).x;
  imageStore(o_window0, p, vec4(1.0, i, j, i * i));
  imageStore(o_window1, p, vec4(j * j, i * j, dx * du + dy * dv, du * du + dv * dv));
  imageStore(o_face, p, ivec4(f));
}

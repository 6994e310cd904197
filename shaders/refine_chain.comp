#version 430 core
// Photometric gradient, last pass: the chain rule per pixel (docs/design/refine.md "Its gradient"):
// dE/dd = -(I G*a - G*(a mu_I) - J G*b + G*(b mu_J)) dJ/dd, written with what the vertices need
// from the pixel: (dE/dd / cos, parallax^2 / cos^2, phi0, phi1). The CPU sums them per face.
layout(local_size_x = 16, local_size_y = 8) in;

#include "refine_faces.glsl"

layout(binding = 0, rgba32f) readonly uniform image2D u_window0;  // m, I, J, -
layout(binding = 1, rgba32f) readonly uniform image2D u_window1;  // -, -, dJ/dd, parallax^2
layout(binding = 2, rgba32f) readonly uniform image2D u_filtered;  // G*a, G*(a mu_I), G*b, G*(b mu_J)
layout(binding = 3, r32i) readonly uniform iimage2D u_face;
layout(binding = 4, rgba32f) writeonly uniform image2D o_chain;

uniform ivec2 u_size;

void main() {
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (p.x >= u_size.x || p.y >= u_size.y) return;
  int f = imageLoad(u_face, p).x;
  if (f < 0) return;  // the CPU reads nothing here
  vec4 w0 = imageLoad(u_window0, p);
  vec4 w1 = imageLoad(u_window1, p);
  vec4 g = imageLoad(u_filtered, p);
  float dncc_dj = w0.y * g.x - g.y - w0.z * g.z + g.w;
  float de_dd = -dncc_dj * w1.z;
  RefineFace face = u_faces[f];
  vec3 ray = PixelRay(p);
  float cos_incidence = dot(face.unit_offset.xyz, ray);
  vec3 x = (face.unit_offset.w / cos_incidence) * ray;
  float phi0 = dot(x - face.p1.xyz, face.g0.xyz);
  float phi1 = dot(x - face.p2.xyz, face.g1.xyz);
  imageStore(o_chain, p, vec4(de_dd / cos_incidence, w1.w / (cos_incidence * cos_incidence),
                              phi0, phi1));
}

// The mesh's faces as the refinement's GLSL gradient kernel sees them (refine/glsl_gradient.cc),
// relative to the reference camera's centre C: a pixel's unit ray r meets face f's plane at
// C + d r with d = offset / (unit . r); the point's barycentric weights are
// phi0 = (x - p1) . g0, phi1 = (x - p2) . g1, phi2 = 1 - phi0 - phi1 (photometric_gradient_fast.cc).
struct RefineFace {
  vec4 unit_offset;  // xyz unit normal, w offset
  vec4 p1;           // xyz, relative to C
  vec4 p2;
  vec4 g0;
  vec4 g1;
};
layout(std430, binding = 0) readonly buffer RefineFaces { RefineFace u_faces[]; };

uniform mat3 u_rt_i;  // R_i^T: the reference's camera frame to world directions
uniform vec4 u_k_i;   // the reference's fx, fy, cx, cy

// The unit world ray through pixel `p` of the reference (pixel centres at +0.5).
vec3 PixelRay(ivec2 p) {
  vec3 c = vec3((float(p.x) + 0.5 - u_k_i.z) / u_k_i.x, (float(p.y) + 0.5 - u_k_i.w) / u_k_i.y, 1.0);
  return normalize(u_rt_i * c);
}

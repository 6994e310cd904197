#version 430 core
// The refinement's Gaussian window, one direction at a time (refine/glsl_gradient.cc): each of
// the four channels of u_in summed with u_weights along rows (u_axis 0) or columns (1), zero
// outside the image, as cv::sepFilter2D with BORDER_CONSTANT.
layout(local_size_x = 16, local_size_y = 8) in;

layout(std430, binding = 1) readonly buffer Weights { float u_weights[]; };  // 2 radius + 1
layout(binding = 0, rgba32f) readonly uniform image2D u_in;
layout(binding = 1, rgba32f) writeonly uniform image2D o_out;

uniform ivec2 u_size;
uniform int u_radius;
uniform int u_axis;

void main() {
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (p.x >= u_size.x || p.y >= u_size.y) return;
  ivec2 step = u_axis == 0 ? ivec2(1, 0) : ivec2(0, 1);
  int at = u_axis == 0 ? p.x : p.y;
  int length = u_axis == 0 ? u_size.x : u_size.y;
  int first = max(-u_radius, -at), last = min(u_radius, length - 1 - at);
  vec4 sum = vec4(0.0);
  for (int t = first; t <= last; ++t) sum += u_weights[t + u_radius] * imageLoad(u_in, p + t * step);
  imageStore(o_out, p, sum);
}

#version 430 core
// Mesh sweeping (paper section 2.2, docs/design/sweep.md "Sweeping"): every facet is moved as a whole
// along C's viewing rays, v' = v + alpha_k |cos(theta)| d with d = (v - C)/|v - C| and
// cos(theta) = n.d, n the facet's unit normal from its unswept vertices (zero for a degenerate
// facet, which then does not move). Positive k moves a facet away from C whatever its
// orientation; v' stays on C's ray through v. The swept triangle goes to layer vs_layer (the
// offset's slot in the batch) and is projected with this render's camera (C, or a neighbour for
// its shadow map).
layout(triangles) in;
layout(triangle_strip, max_vertices = 3) out;

in vec3 vs_position[];
flat in int vs_layer[];

uniform vec3 u_center;        // C's centre, relative to the origin
uniform float u_alpha;        // sweep step (scene units)
uniform int u_first_offset;   // k of layer 0
uniform mat4 u_model_view;    // (X - origin) -> this render's camera coordinates
uniform mat4 u_projection;    // camera -> clip (gl/projection.h)

out vec3 gs_world;   // swept position relative to the origin
out float gs_depth;  // camera z of this render's camera

void main() {
  vec3 n = cross(vs_position[1] - vs_position[0], vs_position[2] - vs_position[0]);
  float len = length(n);
  n = len > 0.0 ? n / len : vec3(0.0);
  float alpha_k = u_alpha * float(u_first_offset + vs_layer[0]);
  for (int i = 0; i < 3; ++i) {
    vec3 v = vs_position[i];
    vec3 ray = v - u_center;
    float distance = length(ray);
    vec3 swept = v;
    if (distance > 0.0) {
      vec3 d = ray / distance;
      swept = v + (alpha_k * abs(dot(n, d))) * d;
    }
    vec4 camera = u_model_view * vec4(swept, 1.0);
    gs_world = swept;
    gs_depth = camera.z;
    gl_Position = u_projection * camera;
    gl_Layer = vs_layer[0];
    gl_PrimitiveID = gl_PrimitiveIDIn;  // the face index (restarts with every instance)
    EmitVertex();
  }
  EndPrimitive();
}

#version 430 core
// Mesh geometry for textured rendering (surface.frag).
layout(location = 0) in vec3 a_position;  // relative to u_origin

uniform mat4 u_model_view;
uniform mat4 u_projection;

out vec3 v_world;  // relative to u_origin

void main() {
  v_world = a_position;
  gl_Position = u_projection * (u_model_view * vec4(a_position, 1.0));
}

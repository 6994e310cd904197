#version 430 core
// Mesh geometry for depth rendering (gl/mesh_renderer.cc). Positions are relative to u_origin
// so that float keeps its precision far from the world origin.
layout(location = 0) in vec3 a_position;

uniform mat4 u_model_view;  // (X - origin) -> camera (gl/projection.h ModelView)
uniform mat4 u_projection;  // camera -> clip (gl/projection.h GlProjection)

out vec3 v_camera;  // camera coordinates: z is the metric depth
out vec3 v_world;   // world position relative to u_origin

void main() {
  vec4 camera = u_model_view * vec4(a_position, 1.0);
  v_camera = camera.xyz;
  v_world = a_position;
  gl_Position = u_projection * camera;
}

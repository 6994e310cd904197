#version 430 core
// Per-pixel camera depth, world position and face index of the nearest surface.
in vec3 v_camera;
in vec3 v_world;

uniform vec3 u_origin;

layout(location = 0) out float o_depth;  // camera z (> 0); the target is cleared to 0
layout(location = 1) out vec4 o_world;   // xyz world position, w = 1 where covered
layout(location = 2) out int o_face;     // index of the face in the mesh; cleared to -1

void main() {
  o_depth = v_camera.z;
  o_world = vec4(v_world + u_origin, 1.0);
  o_face = gl_PrimitiveID;
}

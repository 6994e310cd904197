#version 430 core
// Mesh sweeping, rasterization (worker/glsl_sweep.cc, docs/design/sweep.md): the job's mesh, vertices
// relative to the kernel's origin (float precision far from the world origin). One instance per
// offset k of the batch; the geometry shader sweeps each facet and routes it to layer
// gl_InstanceID of the layered target.
layout(location = 0) in vec3 a_position;

out vec3 vs_position;
flat out int vs_layer;

void main() {
  vs_position = a_position;
  vs_layer = gl_InstanceID;
}

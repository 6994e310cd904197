// I_k^j: neighbour j's image reprojected into C through the swept mesh M_k (docs/design/sweep.md,
// "Reprojection"), for C's surface point `world` (relative to the origin) on layer `layer`.
// Valid if the point is in front of the neighbour, projects to (u, v) within
// [0.5, W-0.5] x [0.5, H-0.5] (between texel centres: no clamping needed) and its depth is at
// most (1 + tolerance) x the shadow map's depth at texel (floor(u), floor(v)). The value is
// interpolated by hand from texelFetch at texel coordinates (u - 0.5, v - 0.5) (the filtering
// units of GPUs round their weights to 8 bits).
// Returns what the row-blur pass reads: (m, m (I_C - 0.5), m (J - 0.5), J) with m in {0, 1}
// and J = 0 where invalid; the -0.5 shift keeps float sums of squares precise.
uniform sampler2D u_image;                     // I_C
uniform sampler2D u_neighbour[NEIGHBOURS];     // I_j
uniform sampler2DArray u_shadow[NEIGHBOURS];   // camera z of M_k from neighbour j, per layer
uniform ivec2 u_neighbour_size[NEIGHBOURS];
uniform mat3 u_rotation[NEIGHBOURS];           // R_j
uniform vec3 u_translation[NEIGHBOURS];        // R_j origin + t_j (world relative to the origin)
uniform vec4 u_intrinsics[NEIGHBOURS];         // fx, fy, cx, cy of camera j
uniform float u_occlusion;                     // 1 + occlusion tolerance

vec4 Reproject(int j, vec3 world, int layer, float centred) {
  vec3 x = u_rotation[j] * world + u_translation[j];
  if (!(x.z > 0.0)) return vec4(0.0);
  float u = u_intrinsics[j].x * x.x / x.z + u_intrinsics[j].z;
  float v = u_intrinsics[j].y * x.y / x.z + u_intrinsics[j].w;
  vec2 size = vec2(u_neighbour_size[j]);
  if (!(u >= 0.5 && u <= size.x - 0.5 && v >= 0.5 && v <= size.y - 0.5)) return vec4(0.0);
  ivec2 last = u_neighbour_size[j] - 1;
  ivec2 texel = min(ivec2(u, v), last);
  float shadow = texelFetch(u_shadow[j], ivec3(texel, layer), 0).r;
  if (!(x.z <= shadow * u_occlusion)) return vec4(0.0);
  vec2 s = vec2(u, v) - 0.5;
  ivec2 t0 = min(ivec2(s), last);
  ivec2 t1 = min(t0 + 1, last);
  vec2 f = s - vec2(t0);
  float a = texelFetch(u_neighbour[j], t0, 0).r;
  float b = texelFetch(u_neighbour[j], ivec2(t1.x, t0.y), 0).r;
  float c = texelFetch(u_neighbour[j], ivec2(t0.x, t1.y), 0).r;
  float d = texelFetch(u_neighbour[j], t1, 0).r;
  float top = a + f.x * (b - a);
  float bottom = c + f.x * (d - c);
  float value = top + f.y * (bottom - top);
  return vec4(1.0, centred, value - 0.5, value);
}

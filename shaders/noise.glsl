// Deterministic procedural noise: integer hashing only, so every driver computes the same
// pattern (up to float rounding). Used through #include "noise.glsl".

// PCG-style 3D hash (Jarzynski & Olano 2020, "Hash Functions for GPU Rendering").
uvec3 ms_hash3(uvec3 v) {
  v = v * 1664525u + 1013904223u;
  v.x += v.y * v.z;
  v.y += v.z * v.x;
  v.z += v.x * v.y;
  v ^= v >> 16u;
  v.x += v.y * v.z;
  v.y += v.z * v.x;
  v.z += v.x * v.y;
  return v;
}

// Pseudo-random gradient in [-1,1]^3 for a lattice point.
vec3 ms_gradient(ivec3 cell, uint seed) {
  uvec3 h = ms_hash3(uvec3(cell) + uvec3(seed, seed * 7919u, seed * 104729u));
  return vec3(h & 0xffffu) / 32767.5 - 1.0;
}

// Perlin gradient noise, roughly in [-1, 1], smooth (C2), period-free.
float ms_gradient_noise(vec3 p, uint seed) {
  vec3 cell_f = floor(p);
  ivec3 cell = ivec3(cell_f);
  vec3 f = p - cell_f;
  vec3 u = f * f * f * (f * (f * 6.0 - 15.0) + 10.0);
  float n000 = dot(ms_gradient(cell + ivec3(0, 0, 0), seed), f - vec3(0, 0, 0));
  float n100 = dot(ms_gradient(cell + ivec3(1, 0, 0), seed), f - vec3(1, 0, 0));
  float n010 = dot(ms_gradient(cell + ivec3(0, 1, 0), seed), f - vec3(0, 1, 0));
  float n110 = dot(ms_gradient(cell + ivec3(1, 1, 0), seed), f - vec3(1, 1, 0));
  float n001 = dot(ms_gradient(cell + ivec3(0, 0, 1), seed), f - vec3(0, 0, 1));
  float n101 = dot(ms_gradient(cell + ivec3(1, 0, 1), seed), f - vec3(1, 0, 1));
  float n011 = dot(ms_gradient(cell + ivec3(0, 1, 1), seed), f - vec3(0, 1, 1));
  float n111 = dot(ms_gradient(cell + ivec3(1, 1, 1), seed), f - vec3(1, 1, 1));
  float x00 = mix(n000, n100, u.x), x10 = mix(n010, n110, u.x);
  float x01 = mix(n001, n101, u.x), x11 = mix(n011, n111, u.x);
  return mix(mix(x00, x10, u.y), mix(x01, x11, u.y), u.z);
}

// Fractal sum of `octaves` noise layers, each twice the frequency and `gain` times the
// amplitude of the previous one; normalised to roughly [-1, 1].
float ms_fbm(vec3 p, int octaves, float gain, uint seed) {
  float sum = 0.0, amplitude = 1.0, norm = 0.0;
  for (int i = 0; i < octaves; ++i) {
    sum += amplitude * ms_gradient_noise(p, seed + uint(i) * 31u);
    norm += amplitude;
    amplitude *= gain;
    p = p * 2.0 + vec3(0.37, 0.11, 0.73);  // shift so lattices of octaves do not line up
  }
  return sum / norm;
}

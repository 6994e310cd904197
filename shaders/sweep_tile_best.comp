#version 430 core
// Tile-best reduction of one batch of offsets (docs/design/sweep.md "Tile-best"): one work group per
// tile finds the pixel with the highest NCC over the batch's offsets and all neighbours, ties to
// the smaller k, then the earlier neighbour, then the earlier pixel in row-major order, and
// replaces the tile's running best if strictly higher (running bests start at t_NCC; batches run
// in increasing k, so ties keep the earlier batch). A pixel competes only where u_required
// neighbours support it at its offset (its own NCC above t_NCC, the others' above u_support), or
// all that see it if fewer (unless u_strict), and with u_must_move only where its NCC beats the
// same neighbour's at k = 0 (u_unswept_ncc; the batch of k = 0 itself then competes for nothing,
// u_compete = 0). Also counts defined NCC values and covered pixels of the batch for the
// statistics.
layout(local_size_x = REDUCE_THREADS) in;

// imageLoad rather than texelFetch: cheaper on llvmpipe, the same on GPUs.
layout(binding = 0, r32f) readonly uniform image2DArray u_ncc;  // layer b * neighbours + j
// C's render, layer b: xyz, w = face; pixel x at column x + RADIUS.
layout(binding = 1, rgba32f) readonly uniform image2DArray u_world;
// Each neighbour's NCC at k = 0 (layer j), read with u_must_move.
layout(binding = 2, r32f) readonly uniform image2DArray u_unswept_ncc;

layout(std430, binding = 0) readonly buffer TileColumns { int tile_x_begin[]; };  // tiles_x + 1
layout(std430, binding = 1) readonly buffer TileRows { int tile_y_begin[]; };     // tiles_y + 1
layout(std430, binding = 2) buffer BestNcc { float best_ncc[]; };  // per tile, starts at t_NCC
// Per tile: k, winning neighbour (-1: none yet), pixel index row * width + col, face.
layout(std430, binding = 3) buffer BestInfo { ivec4 best_info[]; };
layout(std430, binding = 4) buffer BestPosition { vec4 best_position[]; };  // relative to origin
// Per tile, MATCH_WORDS words: bit j = neighbour j's NCC at the same pixel and k is above t_NCC.
layout(std430, binding = 5) buffer BestMatched { uint best_matched[]; };
// Per batch: defined NCC values, covered pixels.
layout(std430, binding = 6) buffer Counters { uint counters[]; };

uniform int u_layers;         // offsets in this batch
uniform int u_neighbours;
uniform int u_first_offset;   // k of layer 0
uniform int u_width;          // C's image width
uniform int u_batch;          // index of this batch (counter slot)
uniform float u_threshold;    // t_NCC (float, as the reference compares)
uniform int u_required;       // neighbours supporting a winner it needs (WinnerRule)
uniform int u_strict;         // 1: a neighbour that does not see the pixel never supports it
uniform float u_support;      // NCC above which another neighbour supports it
uniform int u_must_move;      // 1: a pixel must match better than the unswept mesh (k = 0)
uniform int u_compete;        // 0: this batch only counts (the unswept batch)

shared float s_ncc[REDUCE_THREADS];
shared int s_layer[REDUCE_THREADS];  // b * neighbours + j
shared int s_index[REDUCE_THREADS];  // pixel index inside the tile (row-major)
shared uint s_defined[REDUCE_THREADS];
shared uint s_covered[REDUCE_THREADS];

// Whether neighbour j's match at pixel p of layer group b has enough support: u_required
// neighbours (j, and the others above u_support), or unless u_strict every one whose NCC is
// defined there (undefined is -2).
bool Supported(ivec2 p, int b, int j) {
  int supporters = 1;
  int defined = 1;
  for (int other = 0; other < u_neighbours; ++other) {
    if (other == j) continue;
    float value = imageLoad(u_ncc, ivec3(p, b * u_neighbours + other)).r;
    if (value > u_support) ++supporters;
    if (value >= -1.0) ++defined;
  }
  return supporters >= (u_strict != 0 ? u_required : min(u_required, defined));
}

// a beats b: higher NCC, or equal and earlier (layer, then pixel).
bool Beats(float ncc_a, int layer_a, int index_a, float ncc_b, int layer_b, int index_b) {
  if (ncc_a != ncc_b) return ncc_a > ncc_b;
  if (layer_a != layer_b) return layer_a < layer_b;
  return index_a < index_b;
}

void main() {
  int tile = int(gl_WorkGroupID.y) * int(gl_NumWorkGroups.x) + int(gl_WorkGroupID.x);
  int x0 = tile_x_begin[gl_WorkGroupID.x];
  int x1 = tile_x_begin[gl_WorkGroupID.x + 1];
  int y0 = tile_y_begin[gl_WorkGroupID.y];
  int y1 = tile_y_begin[gl_WorkGroupID.y + 1];
  int tile_width = x1 - x0;
  int lid = int(gl_LocalInvocationID.x);

  // Each invocation scans its pixels in increasing (layer, index) order; strictly greater
  // keeps the earliest of equal values.
  float ncc = -3.0;  // below every NCC and the undefined value
  int best_layer = 0x7fffffff;
  int best_index = 0x7fffffff;
  uint defined = 0u;
  uint covered = 0u;
  for (int b = 0; b < u_layers; ++b) {
    for (int y = y0; y < y1; ++y) {
      for (int x = x0 + lid; x < x1; x += REDUCE_THREADS) {
        if (imageLoad(u_world, ivec3(x + RADIUS, y, b)).w >= 0.0) ++covered;
      }
    }
    for (int j = 0; j < u_neighbours; ++j) {
      int layer = b * u_neighbours + j;
      // Rows in order and each invocation's columns in order: increasing pixel index.
      for (int y = y0; y < y1; ++y) {
        for (int x = x0 + lid; x < x1; x += REDUCE_THREADS) {
          float value = imageLoad(u_ncc, ivec3(x, y, layer)).r;
          if (value >= -1.0) ++defined;
          // Undefined at k = 0 (UNDEFINED_NCC, below -1): any defined value beats it.
          if (u_compete != 0 && value > ncc &&
              (u_required <= 1 || (value > u_threshold && Supported(ivec2(x, y), b, j))) &&
              (u_must_move == 0 || value > imageLoad(u_unswept_ncc, ivec3(x, y, j)).r)) {
            ncc = value;
            best_layer = layer;
            best_index = (y - y0) * tile_width + (x - x0);
          }
        }
      }
    }
  }
  s_ncc[lid] = ncc;
  s_layer[lid] = best_layer;
  s_index[lid] = best_index;
  s_defined[lid] = defined;
  s_covered[lid] = covered;
  barrier();
  for (int stride = REDUCE_THREADS / 2; stride > 0; stride /= 2) {
    if (lid < stride) {
      int other = lid + stride;
      if (Beats(s_ncc[other], s_layer[other], s_index[other], s_ncc[lid], s_layer[lid],
                s_index[lid])) {
        s_ncc[lid] = s_ncc[other];
        s_layer[lid] = s_layer[other];
        s_index[lid] = s_index[other];
      }
      s_defined[lid] += s_defined[other];
      s_covered[lid] += s_covered[other];
    }
    barrier();
  }
  if (lid != 0) return;
  atomicAdd(counters[2 * u_batch], s_defined[0]);
  atomicAdd(counters[2 * u_batch + 1], s_covered[0]);
  if (!(s_ncc[0] > best_ncc[tile])) return;  // also keeps every value <= t_NCC out
  int b = s_layer[0] / u_neighbours;
  int j = s_layer[0] % u_neighbours;
  ivec2 p = ivec2(x0 + s_index[0] % tile_width, y0 + s_index[0] / tile_width);
  vec4 world = imageLoad(u_world, ivec3(p.x + RADIUS, p.y, b));
  best_ncc[tile] = s_ncc[0];
  best_info[tile] = ivec4(u_first_offset + b, j, p.y * u_width + p.x, int(world.w));
  best_position[tile] = vec4(world.xyz, 0.0);
  for (int w = 0; w < MATCH_WORDS; ++w) best_matched[tile * MATCH_WORDS + w] = 0u;
  for (int other = 0; other < u_neighbours; ++other) {
    if (other == j) continue;
    if (imageLoad(u_ncc, ivec3(p, b * u_neighbours + other)).r > u_threshold) {
      best_matched[tile * MATCH_WORDS + other / 32] |= 1u << uint(other % 32);
    }
  }
}

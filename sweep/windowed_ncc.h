// The fast CPU kernel's NCC (sweep/cpu_sweep.h): WeightedNcc's formula (sweep/reference_sweep.h)
// with the six Gaussian-weighted sums taken by RecursiveGaussian (sweep/recursive_gaussian.h) in
// O(1) per pixel, float32, vectorised, in two streaming passes over the image:
//   1. top to bottom: the vertical causal recursion of the products, stored;
//   2. bottom to top: the vertical anticausal recursion, added to pass 1, and every 8 rows the
//      horizontal recursions (8 rows in the SIMD lanes) and the NCC of those rows.
// On a machine with AVX-512 the passes take 16 floats at a time (the same values bit for bit).
// A workspace for one image size; reuse it across slabs (one per thread).
#pragma once

#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <vector>

#include "base/large_buffer.h"
#include "sweep/recursive_gaussian.h"

namespace ms {

struct RowInputs;  // windowed_ncc.cc

class WindowedNcc {
 public:
  // kWidest: the widest vectors the machine has; k8Floats: AVX2's width everywhere (for tests).
  enum class Vectors { kWidest, k8Floats };
  WindowedNcc(int width, int height, double sigma_px, double min_texture_variance,
              double min_window_weight, Vectors vectors = Vectors::kWidest);
  static bool MachineHasAvx512();

  // I: C's image (CV_32F, width x height).
  void SetCamera(const cv::Mat& image);
  // J: the reprojected neighbour minus 0.5 where valid, 0 elsewhere; mask: 1 where valid, 0
  // elsewhere (row-major, width x height). Writes NCC (NaN where undefined, as WeightedNcc)
  // into `ncc` and returns the number of defined pixels. The passes run over the rectangle
  // around the valid pixels only, with the same results as over the whole image.
  int64_t Run(const float* J, const float* mask, float* ncc);

  static constexpr int kQuantities = 6;    // m, mI, J, mI^2, J^2, IJ
  static constexpr int kLanes = 8;         // rows per block
  static constexpr int kColumnGroup = 16;  // columns interleaved in the vertical passes' rows

 private:
  // Where the passes run: whole blocks of rows and groups of columns (cols 0: no valid pixel).
  struct Window {
    int first_row = 0, last_row = -1, first_col = 0, cols = 0;
  };
  Window ValidWindow() const;
  // The window's part of the rows behind the quantities at `row` (zeros outside the image).
  RowInputs Inputs(int row) const;
  void FinishBlock(int first_row, float* ncc, int64_t* defined);

  int width_, height_;
  RecursiveGaussian gaussian_;
  double min_texture_variance_, min_window_weight_;
  bool avx512_;
  const float* J_ = nullptr;
  const float* mask_ = nullptr;
  Window window_;
  LargeBuffer<float> i_;       // I - 0.5
  LargeBuffer<float> causal_;  // pass 1: [row][col / 16][quantity][col % 16]
  // The passes' own buffers are cache-line aligned too (LargeBuffer): their vectors of 16 floats
  // then never straddle two lines.
  LargeBuffer<float> state_;  // vertical recursions: [col / 16][quantity][4][col % 16]
  LargeBuffer<float> zeros_;  // one row
  // The 8 rows of a block as pass 2 makes them ([quantity][lane][col], each quantity's rows 16
  // floats further on than a plain array, so that the six never share cache sets), then
  // transposed for the horizontal recursions ([quantity / 2][col][quantity % 2][lane]) and their
  // sums.
  LargeBuffer<float> rows_, block_, sums_;
  size_t RowsOffset(int q, int lane) const {
    return q * (static_cast<size_t>(kLanes) * width_ + 16) + static_cast<size_t>(lane) * width_;
  }
};

}  // namespace ms

// Subnormal floats flushed to zero on this thread while a scope runs. The NCC's recursive
// Gaussians (sweep/windowed_ncc.h) decay through subnormals wherever the mask leaves a gap: the
// truncation that ends a window subtracts the sample leaving it, and what remains of the state
// shrinks by the pole's modulus every step. Intel processors take a microcode assist for each
// operation on a subnormal, many times the cost of a normal one, and a full-size job's NCC
// slows several-fold (docs/design/performance.md, "Subnormal floats"). A value that small never
// changes a sum of
// normal values, so every NCC a mask defines stays the same. x86 only (MXCSR's flush-to-zero and
// denormals-are-zero bits); elsewhere nothing changes.
#pragma once

#if defined(__x86_64__) || defined(__i386__)
#include <xmmintrin.h>
#endif

namespace ms {

class ScopedFlushSubnormals {
 public:
  ScopedFlushSubnormals() {
#if defined(__x86_64__) || defined(__i386__)
    saved_ = _mm_getcsr();
    _mm_setcsr(saved_ | kFlushToZero | kSubnormalsAreZero);
#endif
  }
  ~ScopedFlushSubnormals() {
#if defined(__x86_64__) || defined(__i386__)
    _mm_setcsr(saved_);
#endif
  }
  ScopedFlushSubnormals(const ScopedFlushSubnormals&) = delete;
  ScopedFlushSubnormals& operator=(const ScopedFlushSubnormals&) = delete;

 private:
  static constexpr unsigned kFlushToZero = 0x8000, kSubnormalsAreZero = 0x0040;  // MXCSR bits
  unsigned saved_ = 0;
};

}  // namespace ms

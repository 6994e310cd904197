// MS_VECTOR_CLONES: a hot loop compiled twice, for AVX2+FMA (x86-64-v3) and for the x86-64
// baseline, the loader picking one per machine (GCC's target_clones), so one binary runs on every
// node and still vectorises 8 floats wide where it can. Elsewhere (other compilers or CPUs) the
// loop is compiled once. MS_HAVE_AVX2_DISPATCH: hand-written AVX2 code may be compiled (and is
// chosen at run time with __builtin_cpu_supports).
#pragma once

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define MS_VECTOR_CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define MS_VECTOR_CLONES
#endif

#if defined(__x86_64__) && defined(__GNUC__)
#define MS_HAVE_AVX2_DISPATCH 1
#else
#define MS_HAVE_AVX2_DISPATCH 0
#endif

// MS_HAVE_AVX512_DISPATCH: MS_AVX512 functions (x86-64-v4: AVX-512 F, BW, CD, DQ, VL) may be
// compiled, and called where __builtin_cpu_supports("x86-64-v4").
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define MS_HAVE_AVX512_DISPATCH 1
#define MS_AVX512 __attribute__((target("arch=x86-64-v4")))
#else
#define MS_HAVE_AVX512_DISPATCH 0
#define MS_AVX512
#endif

#pragma once
/// \file cpu_features.hpp
/// (Private to the core library, not installed.) What the CPU running the library offers beyond
/// the build's baseline, checked once: the loops that have an AVX2 form (each lane doing the
/// scalar code's operations in its order, so the same values) choose it by this.

namespace gseg {
namespace detail {

/// Whether the CPU executes AVX2 instructions (x86-64 with GCC or Clang; false elsewhere).
inline bool cpuHasAvx2() {
#if defined(__GNUC__) && defined(__x86_64__)
    static const bool has = (__builtin_cpu_init(), __builtin_cpu_supports("avx2") != 0);
    return has;
#else
    return false;
#endif
}

}  // namespace detail
}  // namespace gseg

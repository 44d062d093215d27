// Whether this test file is compiled under a sanitizer that replaces the allocator (ASan or TSan),
// as GCC says it (__SANITIZE_ADDRESS__, __SANITIZE_THREAD__) and as clang does (__has_feature).
// Tests that count allocations or cap the address space check PONYHOP_ALLOCATOR_SANITIZED.
#pragma once

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define PONYHOP_ALLOCATOR_SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define PONYHOP_ALLOCATOR_SANITIZED 1
#endif
#endif
#ifndef PONYHOP_ALLOCATOR_SANITIZED
#define PONYHOP_ALLOCATOR_SANITIZED 0
#endif

// The sanitizer tree of `make test-asan` (CMakeLists.txt defines PONYHOP_SANITIZED there), where
// the physics runs 20-40 times slower than in the Release tree: a test whose measurement is long
// measures a shorter stretch there (the point of that run is memory and undefined behaviour on
// every code path, not the motion), and the Release tree keeps the full measurement.
namespace ponyhop::testing {
#ifdef PONYHOP_SANITIZED
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif
// `full` in the normal build, `shorter` in the sanitizer tree.
template <class T>
constexpr T fullOrSanitized(T full, T shorter) {
  return kSanitized ? shorter : full;
}
}  // namespace ponyhop::testing

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

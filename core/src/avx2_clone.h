// Internal to libgsf: GSF_AVX2_CLONE marks a hot loop function to be compiled twice on x86-64 Linux,
// as an AVX2 clone and the baseline, picked at load time (ifunc). The clone does the same +, -, *, /
// on every lane in the same order (the files using it are compiled with -ffp-contract=off, and AVX2
// does not include FMA), so its results are bitwise the baseline's; only 8 lanes a vector instead of 4.
// Not under a sanitizer: the clone's ifunc resolver runs while the dynamic loader relocates, before the
// sanitizer's runtime is up, and its instrumented code crashes there (ThreadSanitizer: SIGSEGV at start).
#pragma once

#if defined(__SANITIZE_THREAD__) || defined(__SANITIZE_ADDRESS__)
#define GSF_SANITIZED_BUILD 1
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer) || __has_feature(address_sanitizer) || __has_feature(memory_sanitizer)
#define GSF_SANITIZED_BUILD 1
#endif
#endif
#if defined(__x86_64__) && defined(__linux__) && defined(__GNUC__) && !defined(GSF_NO_TARGET_CLONES) && \
    !defined(GSF_SANITIZED_BUILD)
#define GSF_AVX2_CLONE __attribute__((target_clones("avx2", "default")))
#define GSF_VECTOR_FLOATS 8  // floats a vector of the widest clone holds (AVX2)
#else
#define GSF_AVX2_CLONE
#define GSF_VECTOR_FLOATS 4  // SSE2, NEON
#endif

// A loop helper of a cloned function: inlined, so the clone compiles it for AVX2 too (a call would run
// the baseline's code).
#if defined(__GNUC__)
#define GSF_ALWAYS_INLINE inline __attribute__((always_inline))
#else
#define GSF_ALWAYS_INLINE inline
#endif

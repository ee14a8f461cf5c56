/* volley public API: VOLLEY_API, the mark on every entity the shared library exports.
 * Plain C and C++ (included by volley.h and the C++ headers).
 *
 * The library is compiled with -fvisibility=hidden, so only declarations marked
 * VOLLEY_API appear in the dynamic symbol table of libvolley.so; everything else (the
 * BVH builder, the kernels, the oracle) stays internal. For users of the header the mark
 * is harmless: it also names default visibility, which is what they had anyway. With the
 * static archive it has no effect. ELF platforms with GCC or Clang only (the platforms
 * volley builds on). */
#ifndef VOLLEY_EXPORT_H
#define VOLLEY_EXPORT_H

/** Marks a function or class as part of the exported API of libvolley.so. */
#if defined(__GNUC__) || defined(__clang__)
#define VOLLEY_API __attribute__((visibility("default")))
#else
#define VOLLEY_API
#endif

#endif /* VOLLEY_EXPORT_H */

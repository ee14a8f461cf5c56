# Sanitizer builds (CMakePresets.json: asan, tsan). VOLLEY_SANITIZE=address runs
# AddressSanitizer with UndefinedBehaviorSanitizer, VOLLEY_SANITIZE=thread runs
# ThreadSanitizer. Both stop at the first report (-fno-sanitize-recover) and turn on
# libstdc++'s bounds assertions. -O1 with line tables only: the per-ISA kernel files are
# large template instantiations, and -O2 -g under ASan made them impractical to compile.
set(VOLLEY_SANITIZE "" CACHE STRING "Sanitizer build: address (ASan + UBSan), thread (TSan) or empty")
set_property(CACHE VOLLEY_SANITIZE PROPERTY STRINGS "" address thread)

if(VOLLEY_SANITIZE STREQUAL "")
  return()
elseif(VOLLEY_SANITIZE STREQUAL "address")
  # float-divide-by-zero stays off: the kernels divide by zero on purpose (IEEE inf for
  # axis-parallel directions, and NaN screened by the comparisons that follow).
  # vptr and function stay off too: their checks need the C++ UBSan runtime, which a C
  # program linking libvolley.so (the package test) does not load.
  set(VOLLEY_SANITIZE_FLAGS -fsanitize=address,undefined -fno-sanitize=vptr,function -fno-sanitize-recover=all)
elseif(VOLLEY_SANITIZE STREQUAL "thread")
  set(VOLLEY_SANITIZE_FLAGS -fsanitize=thread)
  add_compile_definitions(VOLLEY_SANITIZE_THREAD=1)  # core/tsan_one_thread.h
else()
  message(FATAL_ERROR "VOLLEY_SANITIZE='${VOLLEY_SANITIZE}': expected address, thread or empty")
endif()

list(APPEND VOLLEY_SANITIZE_FLAGS -fno-omit-frame-pointer -gline-tables-only)
# The asan preset: every library compiled with libFuzzer's coverage instrumentation too, so
# that the fuzz targets in fuzz/ (which link libFuzzer itself) share the suite's objects.
option(VOLLEY_FUZZ "Build the libFuzzer targets in fuzz/ (clang, VOLLEY_SANITIZE=address)" OFF)
if(VOLLEY_FUZZ)
  add_compile_options(-fsanitize=fuzzer-no-link)
endif()
add_compile_options(${VOLLEY_SANITIZE_FLAGS})
add_compile_definitions(_GLIBCXX_ASSERTIONS VOLLEY_SANITIZED=1)
add_link_options(${VOLLEY_SANITIZE_FLAGS})
# The same flags, as one string, for builds the tests start themselves (the package
# test's consumer project).
string(JOIN " " VOLLEY_SANITIZE_FLAGS_STRING ${VOLLEY_SANITIZE_FLAGS})
message(STATUS "volley: ${VOLLEY_SANITIZE} sanitizer build (${VOLLEY_SANITIZE_FLAGS_STRING}); "
               "the benchmark suites and their perf.* tests are left out (timings and instruction counts "
               "of instrumented code mean nothing)")

# The package test (cmake -P): install volley from the build tree to a temporary prefix,
# move the prefix (the package must be relocatable), check what it holds, then build
# tests/consumer against it with find_package(volley) and pkg-config, run its checks, and
# compare its answers with the installed `volley trace` on the same ray files.
#
# Variables: VOLLEY_BUILD_DIR, VOLLEY_SOURCE_DIR, VOLLEY_CONFIG (build type), WORK_DIR
# (emptied first), CXX_COMPILER (optional: the compiler of the main build).
cmake_minimum_required(VERSION 3.22)
foreach(var VOLLEY_BUILD_DIR VOLLEY_SOURCE_DIR WORK_DIR)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "run_consumer_test.cmake: pass -D${var}=...")
  endif()
endforeach()
if(NOT VOLLEY_CONFIG)
  set(VOLLEY_CONFIG Release)
endif()

# Runs a command; stops the test with its output when it fails.
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
  string(JOIN " " line ${ARGN})
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "FAILED (${rc}): ${line}\n${out}")
  endif()
  message(STATUS "ok: ${line}")
  set(run_output "${out}" PARENT_SCOPE)
endfunction()

file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
set(stage ${WORK_DIR}/stage)
set(prefix ${WORK_DIR}/prefix)

# 1. Install, then move: nothing in the tree may remember where it was installed.
run(${CMAKE_COMMAND} --install ${VOLLEY_BUILD_DIR} --prefix ${stage} --config ${VOLLEY_CONFIG})
file(RENAME ${stage} ${prefix})
file(GLOB_RECURSE tree RELATIVE ${prefix} LIST_DIRECTORIES false ${prefix}/*)
list(SORT tree)
string(JOIN "\n  " listing ${tree})
message(STATUS "installed (then moved to ${prefix}):\n  ${listing}")

# 2. The tree holds the public headers only, and they include only the standard library
#    and each other (no GLM, xsimd or oneTBB types reach an embedder).
file(GLOB headers RELATIVE ${prefix}/include/volley ${prefix}/include/volley/*)
list(SORT headers)
set(expected_headers accel.h export.h options.h packet.h point.h ray.h volley.h volley_excluding.h volley_masked.h volley_queries.h volley_types.h)
if(NOT headers STREQUAL expected_headers)
  message(FATAL_ERROR "include/volley holds [${headers}], expected [${expected_headers}]")
endif()
foreach(h IN LISTS headers)
  file(STRINGS ${prefix}/include/volley/${h} includes REGEX "^[ \t]*#[ \t]*include")
  foreach(inc IN LISTS includes)
    if(NOT inc MATCHES "^#include (<[a-z_]+(\\.h)?>|\"volley/[a-z_]+\\.h\")$")
      message(FATAL_ERROR "include/volley/${h}: '${inc}' is neither a standard header nor a volley header")
    endif()
  endforeach()
endforeach()
foreach(f lib/libvolley.a lib/cmake/volley/volleyConfig.cmake lib/cmake/volley/volleyConfigVersion.cmake
          lib/pkgconfig/volley.pc bin/volley share/doc/volley/LICENSE)
  if(NOT EXISTS ${prefix}/${f})
    message(FATAL_ERROR "the installed tree lacks ${f}")
  endif()
endforeach()
file(GLOB sonames ${prefix}/lib/libvolley.so.*)
if(NOT sonames)
  message(FATAL_ERROR "the installed tree lacks a versioned libvolley.so.*")
endif()

# 3. Build the consumer against the moved prefix and run its checks.
set(ENV{PKG_CONFIG_PATH} ${prefix}/lib/pkgconfig)
set(consumer_args -S ${VOLLEY_SOURCE_DIR}/tests/consumer -B ${WORK_DIR}/build
    -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_BUILD_TYPE=${VOLLEY_CONFIG})
if(CXX_COMPILER)
  list(APPEND consumer_args -DCMAKE_CXX_COMPILER=${CXX_COMPILER})
endif()
run(${CMAKE_COMMAND} ${consumer_args})
run(${CMAKE_COMMAND} --build ${WORK_DIR}/build --config ${VOLLEY_CONFIG} -j 2)
run(${CMAKE_CTEST_COMMAND} --test-dir ${WORK_DIR}/build -C ${VOLLEY_CONFIG} --output-on-failure)
message(STATUS "${run_output}")
# A pure C project (no CXX language) with COMPONENTS shared.
run(${CMAKE_COMMAND} -S ${VOLLEY_SOURCE_DIR}/tests/consumer/c_only -B ${WORK_DIR}/c_only
    -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_BUILD_TYPE=${VOLLEY_CONFIG})
run(${CMAKE_COMMAND} --build ${WORK_DIR}/c_only --config ${VOLLEY_CONFIG})
run(${WORK_DIR}/c_only/example_c_only)

# 4. The consumer's answers equal `volley trace` (the installed command) on the same ray
#    files: the unit sphere of scenes/meshes on a floor before a wall (quads with negative
#    indices, so the consumer's OBJ reader and volley's must agree on fan triangulation),
#    primary, shadow and diffuse rays, closest hit and occlusion.
file(READ ${VOLLEY_SOURCE_DIR}/scenes/meshes/sphere.obj sphere)
file(WRITE ${WORK_DIR}/scene.obj "${sphere}
v -2.5 -1 -1.5\nv 2.5 -1 -1.5\nv 2.5 -1 2.5\nv -2.5 -1 2.5\nf -1 -2 -3 -4
v -2.5 -1 -1.5\nv 2.5 -1 -1.5\nv 2.5 3 -1.5\nv -2.5 3 -1.5\nf -4 -3 -2 -1\n")
set(volley ${prefix}/bin/volley)
foreach(workload primary shadow diffuse)
  set(rays ${WORK_DIR}/${workload}.vray)
  run(${volley} rays ${WORK_DIR}/scene.obj --workload ${workload} --width 128 --height 96 -o ${rays})
  run(${volley} trace ${WORK_DIR}/scene.obj --rays ${rays} -o ${WORK_DIR}/${workload}.vhit --reps 1)
  run(${WORK_DIR}/build/trace_compare ${WORK_DIR}/scene.obj ${rays} ${WORK_DIR}/${workload}.vhit)
  message(STATUS "${run_output}")
  run(${volley} trace ${WORK_DIR}/scene.obj --rays ${rays} --occluded -o ${WORK_DIR}/${workload}-occluded.vhit --reps 1)
  run(${WORK_DIR}/build/trace_compare ${WORK_DIR}/scene.obj ${rays} ${WORK_DIR}/${workload}-occluded.vhit --occluded)
  message(STATUS "${run_output}")
endforeach()
# Another test and the scalar oracle, to show the comparison follows the options.
run(${volley} trace ${WORK_DIR}/scene.obj --rays ${WORK_DIR}/diffuse.vray --test moller --isa scalar
    -o ${WORK_DIR}/diffuse-moller.vhit --reps 1)
run(${WORK_DIR}/build/trace_compare ${WORK_DIR}/scene.obj ${WORK_DIR}/diffuse.vray ${WORK_DIR}/diffuse-moller.vhit
    --test moller --isa scalar)
message(STATUS "${run_output}")

# 5. README.md shows the two examples exactly as compiled and run above.
file(READ ${VOLLEY_SOURCE_DIR}/README.md readme)
foreach(example example.cpp example.c)
  file(READ ${VOLLEY_SOURCE_DIR}/tests/consumer/${example} text)
  string(FIND "${readme}" "${text}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "README.md does not contain tests/consumer/${example} verbatim: update the README section \"Embedding volley\"")
  endif()
endforeach()
message(STATUS "package test passed")

# volley as a package others embed (README "Embedding volley"). Included from the
# top-level CMakeLists.txt after src/ and simd/, whose targets it uses.
#
#   cmake --install build/release --prefix P   gives a relocatable tree:
#     P/include/volley/{accel,export,options,packet,ray,volley}.h   the public headers only
#     P/lib/libvolley.so -> .so.<major.minor> -> .so.<version>    exports only the API
#     P/lib/libvolley.a                                             self-contained (+ oneTBB)
#     P/lib/cmake/volley/volleyConfig.cmake (+ ConfigVersion, targets)
#     P/lib/pkgconfig/volley.pc
#     P/bin/volley                                                  the command
#
# Both libraries are made of the objects of the in-tree libraries the Accel needs
# (volley: Accel + C API; volley_core: oracle and BVH builder; volley_simd and its per-ISA
# objects: the kernels), compiled once, position-independent and with hidden visibility,
# so that only declarations marked VOLLEY_API (volley/export.h) are exported. The in-tree
# executables keep linking the in-tree static libraries; for them nothing changes but
# -fPIC (with hidden visibility it costs nothing on x86-64).
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

# The version in volley.h must be the project's (volley_version() and the macros).
file(STRINGS ${PROJECT_SOURCE_DIR}/src/volley/volley.h VOLLEY_HEADER_VERSION
     REGEX "^#define VOLLEY_VERSION_(MAJOR|MINOR|PATCH) ")
foreach(part MAJOR MINOR PATCH)
  if(NOT VOLLEY_HEADER_VERSION MATCHES "VOLLEY_VERSION_${part} ${PROJECT_VERSION_${part}}[ \n;]")
    message(FATAL_ERROR "src/volley/volley.h: VOLLEY_VERSION_${part} differs from the project version ${PROJECT_VERSION}")
  endif()
endforeach()

# Parts of the package, in link order. A new internal library the Accel links must be
# added here (the shared library links with --no-undefined, so a missing part fails the
# build; the consumer test catches it for the static archive).
set(VOLLEY_PACKAGE_PARTS volley volley_core volley_simd volley_simd_isa)
set_target_properties(${VOLLEY_PACKAGE_PARTS} PROPERTIES
  POSITION_INDEPENDENT_CODE ON
  CXX_VISIBILITY_PRESET hidden
  VISIBILITY_INLINES_HIDDEN ON)
set(VOLLEY_PACKAGE_OBJECTS "")
foreach(part IN LISTS VOLLEY_PACKAGE_PARTS)
  list(APPEND VOLLEY_PACKAGE_OBJECTS $<TARGET_OBJECTS:${part}>)
endforeach()

# 0.x releases may break the ABI with every minor version: the SONAME carries it.
if(PROJECT_VERSION_MAJOR EQUAL 0)
  set(VOLLEY_SOVERSION ${PROJECT_VERSION_MAJOR}.${PROJECT_VERSION_MINOR})
  set(VOLLEY_COMPATIBILITY SameMinorVersion)
else()
  set(VOLLEY_SOVERSION ${PROJECT_VERSION_MAJOR})
  set(VOLLEY_COMPATIBILITY SameMajorVersion)
endif()

set(VOLLEY_PACKAGE_DIR ${PROJECT_BINARY_DIR}/package)
set(VOLLEY_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/volley)
set(VOLLEY_PUBLIC_INCLUDE $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/src> $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)

# libvolley.so. The version script keeps the dynamic symbol table to the API: hidden
# visibility already hides volley's internals, the script also hides the standard-library
# template instantiations (default visibility in libstdc++'s headers) that the objects
# define as weak symbols, and Accel::Impl's members. -Bsymbolic-functions binds the
# library's calls to its own exported functions (C API -> Accel) directly, without PLT.
add_library(volley_shared SHARED ${VOLLEY_PACKAGE_OBJECTS})
target_link_libraries(volley_shared PRIVATE TBB::tbb)
target_include_directories(volley_shared INTERFACE ${VOLLEY_PUBLIC_INCLUDE})
# (A sanitizer build leaves the runtime's symbols to the executable that loads it.)
target_link_options(volley_shared PRIVATE
  $<$<STREQUAL:${VOLLEY_SANITIZE},>:-Wl,--no-undefined>
  -Wl,-Bsymbolic-functions
  -Wl,--version-script=${PROJECT_SOURCE_DIR}/cmake/volley.map)
set_target_properties(volley_shared PROPERTIES
  OUTPUT_NAME volley
  EXPORT_NAME volley_shared
  VERSION ${PROJECT_VERSION}
  SOVERSION ${VOLLEY_SOVERSION}
  LINK_DEPENDS ${PROJECT_SOURCE_DIR}/cmake/volley.map
  LIBRARY_OUTPUT_DIRECTORY ${VOLLEY_PACKAGE_DIR})

# libvolley.a: the same objects in one archive, so a user links one library (and oneTBB).
add_library(volley_static STATIC ${VOLLEY_PACKAGE_OBJECTS})
target_link_libraries(volley_static PRIVATE TBB::tbb)
target_include_directories(volley_static INTERFACE ${VOLLEY_PUBLIC_INCLUDE})
set_target_properties(volley_static PROPERTIES
  OUTPUT_NAME volley
  EXPORT_NAME volley_static
  ARCHIVE_OUTPUT_DIRECTORY ${VOLLEY_PACKAGE_DIR})

install(TARGETS volley_shared EXPORT volleySharedTargets
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT runtime NAMELINK_COMPONENT development)
install(TARGETS volley_static EXPORT volleyStaticTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT development)
# The public headers, named one by one: nothing internal may slip into include/volley.
install(FILES
  ${PROJECT_SOURCE_DIR}/src/volley/accel.h
  ${PROJECT_SOURCE_DIR}/src/volley/export.h
  ${PROJECT_SOURCE_DIR}/src/volley/options.h
  ${PROJECT_SOURCE_DIR}/src/volley/packet.h
  ${PROJECT_SOURCE_DIR}/src/volley/ray.h
  ${PROJECT_SOURCE_DIR}/src/volley/volley.h
  ${PROJECT_SOURCE_DIR}/src/volley/volley_masked.h
  ${PROJECT_SOURCE_DIR}/src/volley/volley_excluding.h
  ${PROJECT_SOURCE_DIR}/src/volley/volley_queries.h
  ${PROJECT_SOURCE_DIR}/src/volley/volley_types.h
  ${PROJECT_SOURCE_DIR}/src/volley/point.h
  DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/volley COMPONENT development)
install(EXPORT volleySharedTargets NAMESPACE volley:: DESTINATION ${VOLLEY_INSTALL_CMAKEDIR} COMPONENT development)
install(EXPORT volleyStaticTargets NAMESPACE volley:: DESTINATION ${VOLLEY_INSTALL_CMAKEDIR} COMPONENT development)

configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/volleyConfig.cmake.in
  ${VOLLEY_PACKAGE_DIR}/volleyConfig.cmake
  INSTALL_DESTINATION ${VOLLEY_INSTALL_CMAKEDIR}
  NO_SET_AND_CHECK_MACRO)
write_basic_package_version_file(${VOLLEY_PACKAGE_DIR}/volleyConfigVersion.cmake
  VERSION ${PROJECT_VERSION}
  COMPATIBILITY ${VOLLEY_COMPATIBILITY})
install(FILES ${VOLLEY_PACKAGE_DIR}/volleyConfig.cmake ${VOLLEY_PACKAGE_DIR}/volleyConfigVersion.cmake
  DESTINATION ${VOLLEY_INSTALL_CMAKEDIR} COMPONENT development)

# pkg-config: prefix found from the .pc file's own folder, so the tree may move.
file(RELATIVE_PATH VOLLEY_PC_PREFIX_FROM_PCDIR
  /prefix/${CMAKE_INSTALL_LIBDIR}/pkgconfig /prefix)
string(REGEX REPLACE "/$" "" VOLLEY_PC_PREFIX_FROM_PCDIR "${VOLLEY_PC_PREFIX_FROM_PCDIR}")
configure_file(${PROJECT_SOURCE_DIR}/cmake/volley.pc.in ${VOLLEY_PACKAGE_DIR}/volley.pc @ONLY)
install(FILES ${VOLLEY_PACKAGE_DIR}/volley.pc
  DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig COMPONENT development)

install(TARGETS volley_cli RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT cli)
# The licence (Apache-2.0) beside the package, as Debian's and pip's layouts put it.
install(FILES ${PROJECT_SOURCE_DIR}/LICENSE DESTINATION ${CMAKE_INSTALL_DOCDIR} COMPONENT development)

if(VOLLEY_BUILD_TESTS)
  # libvolley.so exports the API and nothing else; the second test shows that the check
  # fails on a library that exports other symbols (oneTBB's own).
  add_test(NAME "package: libvolley.so exports only the API"
           COMMAND sh ${PROJECT_SOURCE_DIR}/tests/consumer/check_exports.sh $<TARGET_FILE:volley_shared>)
  add_test(NAME "package: export check rejects a library with other symbols"
           COMMAND sh ${PROJECT_SOURCE_DIR}/tests/consumer/check_exports.sh $<TARGET_FILE:TBB::tbb>)
  set_tests_properties("package: export check rejects a library with other symbols" PROPERTIES
    PASS_REGULAR_EXPRESSION "exports symbols outside the API")
  # One thread rule: every batch call of the C++ API defaults to 0 threads (all cores).
  file(GLOB VOLLEY_PUBLIC_HEADERS ${PROJECT_SOURCE_DIR}/src/volley/*.h)
  add_test(NAME "package: every thread-count default of the C++ API is 0 (all cores)"
           COMMAND sh ${PROJECT_SOURCE_DIR}/tests/consumer/check_thread_defaults.sh ${VOLLEY_PUBLIC_HEADERS})

  # Install to a temporary prefix, move it, build tests/consumer against it with
  # find_package(volley), run it (C++ and C, shared and static, README examples) and
  # compare its answers with `volley trace` on the same ray file.
  add_test(NAME "package: install, find_package(volley), build and run tests/consumer"
           COMMAND ${CMAKE_COMMAND}
             -DVOLLEY_BUILD_DIR=${PROJECT_BINARY_DIR}
             -DVOLLEY_SOURCE_DIR=${PROJECT_SOURCE_DIR}
             -DVOLLEY_CONFIG=$<CONFIG>
             -DWORK_DIR=${PROJECT_BINARY_DIR}/consumer_test
             -DCXX_COMPILER=${CMAKE_CXX_COMPILER}
             -P ${PROJECT_SOURCE_DIR}/tests/consumer/run_consumer_test.cmake)
  set_tests_properties("package: install, find_package(volley), build and run tests/consumer" PROPERTIES
    TIMEOUT 600 PROCESSORS 2)
  if(VOLLEY_SANITIZE)
    # The consumer links the instrumented library: it builds with the same compiler and flags.
    set_property(TEST "package: install, find_package(volley), build and run tests/consumer" APPEND PROPERTY
      ENVIRONMENT "CC=clang;CXX=clang++;CFLAGS=${VOLLEY_SANITIZE_FLAGS_STRING};CXXFLAGS=${VOLLEY_SANITIZE_FLAGS_STRING};LDFLAGS=${VOLLEY_SANITIZE_FLAGS_STRING}")
  endif()
  if(VOLLEY_SANITIZE STREQUAL "thread")
    set_property(TEST "package: install, find_package(volley), build and run tests/consumer" APPEND PROPERTY
      ENVIRONMENT "TSAN_OPTIONS=halt_on_error=1:suppressions=${PROJECT_SOURCE_DIR}/tests/tsan.supp")
  endif()
endif()

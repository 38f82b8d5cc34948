# Compiler settings as INTERFACE targets, linked PRIVATE by every project target.

# Warnings. -Werror only when CULLIDE_WERROR is on (CI turns it on).
add_library(cullide_warnings INTERFACE)
add_library(cullide::warnings ALIAS cullide_warnings)
target_compile_options(cullide_warnings INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor -Wcast-align -Wunused -Woverloaded-virtual
  -Wnull-dereference -Wdouble-promotion -Wformat=2 -Wimplicit-fallthrough
  $<$<BOOL:${CULLIDE_WERROR}>:-Werror>)

# Floating point: determinism is a contract (docs/determinism.md). No contraction into FMA, no
# fast-math, no excess precision (x87 is never used on x86-64, but say it anyway).
add_library(cullide_fp INTERFACE)
add_library(cullide::fp ALIAS cullide_fp)
target_compile_options(cullide_fp INTERFACE -ffp-contract=off -fno-fast-math)
if(CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
  # clang spells it differently and has no -fexcess-precision for C++.
  target_compile_options(cullide_fp INTERFACE -fno-unsafe-math-optimizations)
endif()

# GCC 12's SLP vectorizer drops float rounding: Vec3{double(float(x)), double(float(y)), ...} comes
# out as a plain copy of x and y at -O2 (found by the Embree oracle; pinned by mesh_test, "the
# compiler keeps double -> float -> double rounding"). Rounding to float is part of the raster and
# oracle contracts, so SLP vectorization is off for the affected compilers.
if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU" AND CMAKE_CXX_COMPILER_VERSION VERSION_LESS 13)
  target_compile_options(cullide_fp INTERFACE -fno-tree-slp-vectorize)
endif()

# Sanitizers, applied to everything built in this tree when CULLIDE_SANITIZE is set.
if(CULLIDE_SANITIZE)
  add_compile_options(-fsanitize=${CULLIDE_SANITIZE} -fno-omit-frame-pointer -fno-sanitize-recover=all)
  add_link_options(-fsanitize=${CULLIDE_SANITIZE})
endif()

# Fuzzing: every target in the tree (the libraries above all) gets coverage instrumentation and,
# by default, ASan + UBSan, or libFuzzer would only see the fuzz target's own file. Fuzz targets add
# the libFuzzer main themselves (fuzz/CMakeLists.txt). CULLIDE_FUZZ_SANITIZE picks the sanitizers:
# "address,undefined" (default, CI), "undefined" or "" (coverage only: every target checks its own
# property against a reference, so a campaign build without ASan still finds wrong answers, several
# times faster; scripts/fuzz.sh campaign --fast).
set(CULLIDE_FUZZ_SANITIZE "address,undefined" CACHE STRING
    "Sanitizers of the fuzz build (comma list; empty = coverage instrumentation only)")
if(CULLIDE_BUILD_FUZZERS)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "CULLIDE_BUILD_FUZZERS needs clang (configure with -DCMAKE_CXX_COMPILER=clang++)")
  endif()
  if(CULLIDE_FUZZ_SANITIZE MATCHES "[^a-z,]")
    message(FATAL_ERROR "CULLIDE_FUZZ_SANITIZE must be a comma list of sanitizer names, got '${CULLIDE_FUZZ_SANITIZE}'")
  endif()
  if(CULLIDE_FUZZ_SANITIZE STREQUAL "")
    add_compile_options(-fsanitize=fuzzer-no-link -fno-omit-frame-pointer)
    # Without a sanitizer runtime nothing else defines the coverage callbacks for the programs that
    # are not fuzz targets (the CLI): link libFuzzer's runtime without its main into every program.
    add_link_options(-fsanitize=fuzzer-no-link)
  else()
    add_compile_options(-fsanitize=fuzzer-no-link,${CULLIDE_FUZZ_SANITIZE} -fno-omit-frame-pointer)
    add_link_options(-fsanitize=${CULLIDE_FUZZ_SANITIZE})
  endif()
endif()

# One call for every project target. Build-only: an installed static library must not pass our
# warning and floating-point flags on to the programs that link it.
function(cullide_target_defaults target)
  target_link_libraries(${target} PRIVATE $<BUILD_INTERFACE:cullide::warnings> $<BUILD_INTERFACE:cullide::fp>)
endfunction()

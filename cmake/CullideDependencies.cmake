# Dependency lookup. Every package is optional and has its own CULLIDE_WITH_<NAME> switch, so a build
# never depends on what happens to be installed: a package is used only when its switch is ON *and*
# it is found, and the result is a CULLIDE_HAVE_<NAME> variable. With CULLIDE_STRICT_DEPS=ON a
# package that is switched ON but missing stops the configure step instead of being skipped
# (scripts/test.sh builds that way, so its oracles can never vanish silently).
#
#   library        TBB (threads; serial executor without it: the embedded configuration)
#   front door     Eigen (the libigl-style V/F entry points of cullide/eigen.h, header-only)
#   tests          GMP (rational references), OSMesa, EGL, Vulkan (lavapipe) and Embree (oracles), doctest
#                  (the runner, needed by CULLIDE_BUILD_TESTS)
#   benchmarks     Google Benchmark (needed by CULLIDE_BUILD_BENCHMARKS), and the peers FCL, Bullet,
#                  CGAL (peers_bench, spatialhash_bench)
# None of OSMesa, EGL, Vulkan, Embree, GMP, FCL, Bullet and CGAL is ever linked into a library.

option(CULLIDE_STRICT_DEPS "Fail when a package switched on by CULLIDE_WITH_* is not found" OFF)
option(CULLIDE_WITH_GMP "Use GMP for the rational references of tests and fuzzers" ON)
option(CULLIDE_WITH_FCL "Compare against FCL in the benchmarks" ON)
option(CULLIDE_WITH_BULLET "Compare against Bullet in the benchmarks" ON)
option(CULLIDE_WITH_CGAL "Compare against CGAL in the benchmarks" ON)

set(_cullide_dep_summary "")
# _cullide_dep(<NAME> <switch value> <found value> <what is lost without it>)
function(_cullide_dep name wanted found lost)
  string(TOUPPER "${name}" var)
  if(NOT wanted)
    set(state "off")
    set(CULLIDE_HAVE_${var} OFF PARENT_SCOPE)
  elseif(found)
    set(state "yes")
    set(CULLIDE_HAVE_${var} ON PARENT_SCOPE)
  else()
    set(state "missing")
    set(CULLIDE_HAVE_${var} OFF PARENT_SCOPE)
    if(CULLIDE_STRICT_DEPS)
      message(FATAL_ERROR "cullide: ${name} is switched on but was not found (CULLIDE_STRICT_DEPS=ON); "
                          "install it (scripts/deps.sh) or switch it off. Without it: ${lost}")
    endif()
    message(STATUS "cullide: ${name} not found: ${lost}")
  endif()
  set(_cullide_dep_summary "${_cullide_dep_summary} ${name}=${state}" PARENT_SCOPE)
endfunction()

# oneTBB: the libraries' only third-party dependency (private; the installed package config finds it).
if(CULLIDE_WITH_TBB)
  find_package(TBB QUIET)
endif()
_cullide_dep(TBB "${CULLIDE_WITH_TBB}" "${TBB_FOUND}" "the libraries use the serial executor")

if(CULLIDE_WITH_EIGEN)
  find_package(Eigen3 3.4 QUIET NO_MODULE)
endif()
_cullide_dep(Eigen "${CULLIDE_WITH_EIGEN}" "${Eigen3_FOUND}" "no cullide::eigen target, its tests are skipped")

if(CULLIDE_WITH_OSMESA)
  find_package(PkgConfig QUIET)
  if(PkgConfig_FOUND)
    pkg_check_modules(OSMesa QUIET IMPORTED_TARGET osmesa)
  endif()
endif()
_cullide_dep(OSMesa "${CULLIDE_WITH_OSMESA}" "${OSMesa_FOUND}" "the real-GL conformance checks are skipped")

# Vulkan: the loader and headers (libvulkan-dev) plus glslangValidator (glslang-tools) to build the
# oracle's vertex shader to SPIR-V; the device it looks for at run time is Mesa's lavapipe.
if(CULLIDE_WITH_VULKAN)
  find_package(Vulkan QUIET)
  find_program(CULLIDE_GLSLANG_VALIDATOR glslangValidator)
endif()
set(_cullide_vulkan_found OFF)
if(Vulkan_FOUND AND CULLIDE_GLSLANG_VALIDATOR)
  set(_cullide_vulkan_found ON)
endif()
_cullide_dep(Vulkan "${CULLIDE_WITH_VULKAN}" "${_cullide_vulkan_found}"
             "the Vulkan-rules (lavapipe) conformance checks are skipped")

# EGL: real GL drivers without a window, through glvnd (libegl-dev, libopengl-dev; Mesa's software
# device, llvmpipe, is libegl-mesa0). The EGL oracle (tests/oracle/egl_device.h) runs
# tests/raster/driver_report on llvmpipe here, and on a GPU's own driver where one is.
if(CULLIDE_WITH_EGL)
  set(OpenGL_GL_PREFERENCE GLVND)
  find_package(OpenGL QUIET COMPONENTS OpenGL EGL)
endif()
set(_cullide_egl_found OFF)
if(TARGET OpenGL::OpenGL AND TARGET OpenGL::EGL)
  set(_cullide_egl_found ON)
endif()
_cullide_dep(EGL "${CULLIDE_WITH_EGL}" "${_cullide_egl_found}" "the EGL (real GL driver) reports are not built")

if(CULLIDE_WITH_EMBREE)
  find_package(embree 3 QUIET)
endif()
_cullide_dep(Embree "${CULLIDE_WITH_EMBREE}" "${embree_FOUND}" "the ray-cast interference checks are skipped")

# GMP: the exact rational references of the tests and fuzzers.
set(_cullide_gmp_found OFF)
if(CULLIDE_WITH_GMP)
  find_path(GMPXX_INCLUDE_DIR gmpxx.h)
  find_library(GMPXX_LIBRARY gmpxx)
  find_library(GMP_LIBRARY gmp)
  if(GMPXX_INCLUDE_DIR AND GMPXX_LIBRARY AND GMP_LIBRARY)
    set(_cullide_gmp_found ON)
    add_library(cullide_gmp INTERFACE)
    add_library(cullide::gmp ALIAS cullide_gmp)
    target_include_directories(cullide_gmp INTERFACE ${GMPXX_INCLUDE_DIR})
    target_link_libraries(cullide_gmp INTERFACE ${GMPXX_LIBRARY} ${GMP_LIBRARY})
  endif()
endif()
_cullide_dep(GMP "${CULLIDE_WITH_GMP}" "${_cullide_gmp_found}" "the rational-reference tests and fuzzers are skipped")

if(CULLIDE_BUILD_TESTS)
  find_package(doctest REQUIRED)
  include(doctest)
endif()

if(CULLIDE_BUILD_BENCHMARKS)
  find_package(benchmark QUIET)
endif()
_cullide_dep(benchmark "${CULLIDE_BUILD_BENCHMARKS}" "${benchmark_FOUND}" "the benchmarks are not built")

# Benchmark peers: looked up only when the benchmarks are built ("off" otherwise).
macro(_cullide_peer name switch package)
  set(_want OFF)
  if(${switch} AND CULLIDE_HAVE_BENCHMARK)
    set(_want ON)
    find_package(${package} QUIET ${ARGN})
  endif()
  set(_found OFF)
  if(${package}_FOUND OR ${name}_FOUND)
    set(_found ON)
  endif()
  _cullide_dep(${name} "${_want}" "${_found}" "the benchmarks run without this peer")
endmacro()
_cullide_peer(FCL CULLIDE_WITH_FCL fcl)
_cullide_peer(Bullet CULLIDE_WITH_BULLET Bullet MODULE)
_cullide_peer(CGAL CULLIDE_WITH_CGAL CGAL)

message(STATUS "cullide: dependencies:${_cullide_dep_summary}")

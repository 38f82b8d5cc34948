# Cross-compiling cullide for aarch64 Linux with Debian's cross toolchain (g++-aarch64-linux-gnu),
# the embedded target of docs/reliability.md. Used by scripts/cross-aarch64.sh:
#   cmake -S . -B build-aarch64 -DCMAKE_TOOLCHAIN_FILE=cmake/toolchain-aarch64.cmake \
#         -DCULLIDE_WITH_TBB=OFF -DCULLIDE_WITH_OSMESA=OFF -DCULLIDE_WITH_EMBREE=OFF ...
#
# Binaries are linked statically: the target has no TBB, OSMesa or Embree, and a static binary runs
# under qemu-user without a sysroot (-L) or LD_LIBRARY_PATH, the same way as on a bare board.

# Second use of this file: CMAKE_PROJECT_INCLUDE (set below) runs it again right after project(), once
# CMake's platform files have set CMAKE_FIND_LIBRARY_SUFFIXES to ".so;.a". Static executables need
# the archives (a shared library cannot go into a static link), so only ".a" is looked for.
if(CULLIDE_TOOLCHAIN_PROJECT_HOOK)
  set(CMAKE_FIND_LIBRARY_SUFFIXES .a)
  return()
endif()

set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)

set(CULLIDE_CROSS_TRIPLET aarch64-linux-gnu)
set(CMAKE_C_COMPILER ${CULLIDE_CROSS_TRIPLET}-gcc)
set(CMAKE_CXX_COMPILER ${CULLIDE_CROSS_TRIPLET}-g++)

# Where target files live: the cross toolchain's own tree, and Debian multiarch (libgmp-dev:arm64 puts
# its libraries in /usr/lib/aarch64-linux-gnu, found through CMAKE_LIBRARY_ARCHITECTURE under "/").
# Header-only packages (Eigen, doctest) are architecture independent and found in /usr/share and
# /usr/lib/cmake, so packages and headers are looked up on both sides; libraries only on the target
# side, and the host's multiarch folders are ignored outright so an x86-64 library can never slip in.
set(CMAKE_FIND_ROOT_PATH /usr/${CULLIDE_CROSS_TRIPLET} /)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE BOTH)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE BOTH)
set(CMAKE_IGNORE_PATH /usr/lib/x86_64-linux-gnu /lib/x86_64-linux-gnu /usr/include/x86_64-linux-gnu)

# Static executables; find_library looks for archives only (see the hook at the top).
set(CMAKE_EXE_LINKER_FLAGS_INIT "-static")
set(CULLIDE_TOOLCHAIN_PROJECT_HOOK ON)
set(CMAKE_PROJECT_INCLUDE ${CMAKE_CURRENT_LIST_FILE})

# Test programs (and doctest_discover_tests, which lists the cases at build time) run under
# qemu-user. CULLIDE_QEMU overrides the emulator (e.g. qemu-aarch64-static).
if(NOT CULLIDE_QEMU)
  find_program(CULLIDE_QEMU NAMES qemu-aarch64 qemu-aarch64-static)
endif()
if(CULLIDE_QEMU)
  set(CMAKE_CROSSCOMPILING_EMULATOR ${CULLIDE_QEMU})
endif()

# Installation, the CMake package, pkg-config and the .deb: cullide installs like FCL and Embree do.
#
#   cmake --install build --prefix /opt/cullide
#   find_package(cullide 0.1 CONFIG REQUIRED)      # CMAKE_PREFIX_PATH=/opt/cullide
#   target_link_libraries(app PRIVATE cullide::cullide)   # or cullide::raster, cullide::spatialhash
#   pkg-config --cflags --libs cullide
#   cpack --config build/CPackConfig.cmake          # cullide_<version>_<arch>.deb
#
# The libraries are static by default (BUILD_SHARED_LIBS=ON makes them shared). oneTBB is their
# only dependency, and only when it was built in: the package config then finds it
# (find_dependency), pkg-config lists it, and the .deb depends on libtbb-dev. Oracles and peers are
# never installed. tests/consumer is the downstream project CI builds against the installed tree.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(CULLIDE_INSTALL_CMAKEDIR "${CMAKE_INSTALL_LIBDIR}/cmake/cullide" CACHE STRING
    "Where the CMake package files are installed (relative to the prefix)")

install(TARGETS cullide_outcome cullide_raster cullide_spatialhash cullide_lib EXPORT cullideTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
foreach(module raster/outcome raster spatialhash cullide)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${module}/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
          FILES_MATCHING PATTERN "*.h")
endforeach()
# The Eigen front door is a component of its own (its own export set), so that the package needs
# Eigen only when a consumer asks for it: find_package(cullide CONFIG COMPONENTS eigen).
if(TARGET cullide_eigen)
  install(TARGETS cullide_eigen EXPORT cullideEigenTargets)
  install(EXPORT cullideEigenTargets NAMESPACE cullide:: DESTINATION ${CULLIDE_INSTALL_CMAKEDIR})
endif()
install(TARGETS cullide_cli RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
# The man page is generated from the CLI's option table at build time (absent when cross-compiling).
install(FILES ${CMAKE_BINARY_DIR}/man/cullide.1 DESTINATION ${CMAKE_INSTALL_MANDIR}/man1 OPTIONAL)
install(FILES ${PROJECT_SOURCE_DIR}/README.md DESTINATION ${CMAKE_INSTALL_DOCDIR})

install(EXPORT cullideTargets NAMESPACE cullide:: DESTINATION ${CULLIDE_INSTALL_CMAKEDIR})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/cullideConfig.cmake.in
                              ${CMAKE_BINARY_DIR}/cullideConfig.cmake
                              INSTALL_DESTINATION ${CULLIDE_INSTALL_CMAKEDIR})
# 0.x: minor versions may break the API, so 0.1 accepts 0.1.* only.
write_basic_package_version_file(${CMAKE_BINARY_DIR}/cullideConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_BINARY_DIR}/cullideConfig.cmake ${CMAKE_BINARY_DIR}/cullideConfigVersion.cmake
        DESTINATION ${CULLIDE_INSTALL_CMAKEDIR})

# pkg-config. The prefix is found from the .pc file's own place, so an installed tree can move (and
# `cmake --install --prefix` needs no reconfigure). The libraries are static, so TBB goes in Requires (not Requires.private): a plain
# `pkg-config --libs cullide` must already link.
set(CULLIDE_PC_REQUIRES "")
if(CULLIDE_HAVE_TBB)
  set(CULLIDE_PC_REQUIRES "tbb")
endif()
file(RELATIVE_PATH CULLIDE_PC_TO_PREFIX "/p/${CMAKE_INSTALL_LIBDIR}/pkgconfig" "/p")
string(REGEX REPLACE "/$" "" CULLIDE_PC_TO_PREFIX "${CULLIDE_PC_TO_PREFIX}")
configure_file(${PROJECT_SOURCE_DIR}/cmake/cullide.pc.in ${CMAKE_BINARY_DIR}/cullide.pc @ONLY)
install(FILES ${CMAKE_BINARY_DIR}/cullide.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)

# CPack: one .deb with the CLI, the headers, the libraries and both package descriptions.
set(CPACK_GENERATOR "DEB")
set(CPACK_PACKAGE_NAME "cullide")
set(CPACK_PACKAGE_VENDOR "cullide")
set(CPACK_PACKAGE_CONTACT "cullide developers <cullide@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "${PROJECT_DESCRIPTION}")
set(CPACK_PACKAGE_VERSION "${PROJECT_VERSION}")
set(CPACK_PACKAGING_INSTALL_PREFIX "/usr")
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION "libdevel")
# dpkg-shlibdeps (dpkg-dev) fills in the CLI's shared-library dependencies (libc6, libstdc++6,
# libtbb12) from the binary itself; the static libraries also need the TBB development files.
find_program(CULLIDE_DPKG_SHLIBDEPS dpkg-shlibdeps)
if(CULLIDE_DPKG_SHLIBDEPS)
  set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
endif()
if(CULLIDE_HAVE_TBB)
  set(CPACK_DEBIAN_PACKAGE_DEPENDS "libtbb-dev")
endif()
if(TARGET cullide_eigen)
  set(CPACK_DEBIAN_PACKAGE_SUGGESTS "libeigen3-dev")  # for the cullide::eigen component only
endif()
include(CPack)

# Debian packages, one per installation component, made by CPack:
#   cmake -S . -B build-deb -DCMAKE_INSTALL_PREFIX=/usr -DBUILD_SHARED_LIBS=ON \
#     -DCMAKE_BUILD_TYPE=Release -DSTICKSLIP_BUILD_TESTS=OFF -DSTICKSLIP_BUILD_BENCH=OFF
#   cmake --build build-deb && (cd build-deb && cpack -G DEB)
# gives libstickslip0 (the shared library), libstickslip-dev (the header, the
# static library, the pkg-config files and the CMake package) and stickslipd
# (the daemon, its man page, its systemd unit and its documents).  The
# libraries each package needs are read from its binaries (dpkg-shlibdeps).
set(CPACK_PACKAGE_NAME stickslip)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_CONTACT
  "stickslip maintainers <maintainers@users.noreply.h-seed-b41899f8.example>")
set(CPACK_RESOURCE_FILE_LICENSE ${PROJECT_SOURCE_DIR}/LICENSE)
set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_COMPONENTS_ALL lib dev)
if(STICKSLIP_BUILD_SERVER)
  list(APPEND CPACK_COMPONENTS_ALL daemon)
endif()
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_RELEASE 1)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_ENABLE_COMPONENT_DEPENDS ON)

set(CPACK_DEBIAN_LIB_PACKAGE_NAME libstickslip0)
set(CPACK_DEBIAN_LIB_PACKAGE_SECTION libs)
# its shlibs file ("=": a 0.x minor version may break the ABI) and the
# ldconfig trigger, as Debian's own library packages have them (not a
# postinst that runs ldconfig, which fails in a root of its own)
configure_file(${PROJECT_SOURCE_DIR}/packaging/deb/shlibs.in
  ${PROJECT_BINARY_DIR}/deb-control/shlibs @ONLY)
set(CPACK_DEBIAN_LIB_PACKAGE_CONTROL_EXTRA ${PROJECT_BINARY_DIR}/deb-control/shlibs
  ${PROJECT_SOURCE_DIR}/packaging/deb/triggers)
set(CPACK_DEBIAN_LIB_DESCRIPTION "periodic orbits of a two-mass oscillator with Coulomb friction
libstickslip computes the motions of M. Pascal's two-mass oscillator with
Coulomb friction (2011) exactly: modal closed forms within each mode,
certified event location, periodic orbits and their stability, families,
maps and basins.

This package holds the shared library.")

set(CPACK_DEBIAN_DEV_PACKAGE_NAME libstickslip-dev)
set(CPACK_DEBIAN_DEV_PACKAGE_SECTION libdevel)
set(CPACK_COMPONENT_DEV_DEPENDS lib)
# GSL's headers and libraries: the header's users and a static link need them
set(CPACK_DEBIAN_DEV_PACKAGE_DEPENDS "libgsl-dev")
set(CPACK_DEBIAN_DEV_DESCRIPTION "periodic orbits of a two-mass oscillator with Coulomb friction (development files)
libstickslip computes the motions of M. Pascal's two-mass oscillator with
Coulomb friction (2011) exactly.

This package holds the header stickslip.h, the static library, the
pkg-config files stickslip.pc and stickslip-static.pc, and the CMake
package (find_package(stickslip)).")

set(CPACK_DEBIAN_DAEMON_PACKAGE_NAME stickslipd)
set(CPACK_DEBIAN_DAEMON_PACKAGE_SECTION science)
set(CPACK_DEBIAN_DAEMON_DESCRIPTION "periodic orbits of a dry-friction oscillator over HTTP/JSON
stickslipd answers libstickslip's computations (orbits, simulations,
stability, families, maps, basins, batches and jobs) over HTTP/JSON, with
fair queues per client, limits, metrics and an explorer for the browser.

The systemd unit stickslipd.service runs it on 127.0.0.1:8080 as a
dynamic user; it is not enabled on installation.")
# systemd reads the unit after an installation or a removal
# the daemon links the shared library of this build: its dependency is the
# package of the same version, not one dpkg-shlibdeps would look up
set(CPACK_COMPONENT_DAEMON_DEPENDS lib)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS_PRIVATE_DIRS ${PROJECT_BINARY_DIR})
set(CPACK_DEBIAN_DAEMON_PACKAGE_CONTROL_EXTRA
  ${PROJECT_SOURCE_DIR}/packaging/deb/postinst
  ${PROJECT_SOURCE_DIR}/packaging/deb/postrm)
set(CPACK_DEBIAN_DAEMON_PACKAGE_CONTROL_STRICT_PERMISSION ON)

# each package's copyright file, where Debian looks for it (only in the
# packages: a plain installation has the licence once, in the daemon's
# documents)
foreach(_c lib dev daemon)
  string(TOUPPER ${_c} _C)
  install(FILES ${PROJECT_SOURCE_DIR}/LICENSE RENAME copyright
    DESTINATION ${CMAKE_INSTALL_DATAROOTDIR}/doc/${CPACK_DEBIAN_${_C}_PACKAGE_NAME}
    COMPONENT ${_c} EXCLUDE_FROM_ALL)
endforeach()

include(CPack)

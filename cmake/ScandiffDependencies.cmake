# SPDX-License-Identifier: GPL-3.0-or-later
# Finds every dependency once, here. A missing one stops the configure step with
# the Debian package that provides it (scripts/install-deps.sh installs them all).

macro(scandiff_require PACKAGE DEBIAN_PACKAGE)
  find_package(${PACKAGE} ${ARGN} QUIET)
  if(NOT ${PACKAGE}_FOUND)
    message(FATAL_ERROR "scandiff needs ${PACKAGE}: install the Debian package '${DEBIAN_PACKAGE}' "
                        "(or run scripts/install-deps.sh, which installs every dependency).")
  endif()
endmacro()

scandiff_require(Eigen3 libeigen3-dev 3.3 NO_MODULE)
scandiff_require(TBB libtbb-dev)
scandiff_require(muparser libmuparser-dev)
scandiff_require(liblzf liblzf-dev)
scandiff_require(CLI11 libcli11-dev)
scandiff_require(nlohmann_json nlohmann-json3-dev)
scandiff_require(PCL libpcl-dev 1.12 COMPONENTS common kdtree search)
scandiff_require(CGAL libcgal-dev)

if(SCANDIFF_BUILD_GUI)
  scandiff_require(Qt5 qtbase5-dev COMPONENTS Widgets Test)
  # Debian 12's VTK 9.1 resolves VTK::mpi only when MPI's C component was found first.
  scandiff_require(MPI libopenmpi-dev COMPONENTS C)
  scandiff_require(VTK libvtk9-qt-dev COMPONENTS GUISupportQt RenderingOpenGL2 RenderingCore
                   InteractionStyle InteractionWidgets RenderingAnnotation RenderingLabel CommonCore CommonDataModel IOImage)
endif()
if(SCANDIFF_BUILD_TESTS)
  scandiff_require(GTest "libgtest-dev libgmock-dev")
endif()
if(SCANDIFF_BUILD_BENCH)
  scandiff_require(benchmark libbenchmark-dev)
endif()

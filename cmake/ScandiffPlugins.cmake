# SPDX-License-Identifier: GPL-3.0-or-later
# A plugin is a folder plugins/NAME with a CMakeLists.txt that calls
#   scandiff_add_plugin(NAME SOURCES ... [PRIVATE_LIBS ...])
# and a src/ file defining   void scandiff_register_plugin_NAME(scandiff::PluginRegistry&).
# The plugins/ CMakeLists generates the function that calls every registration,
# so front ends and tests get all plugins by linking scandiff_plugins.

set_property(GLOBAL PROPERTY SCANDIFF_PLUGINS "")

function(scandiff_add_plugin NAME)
  cmake_parse_arguments(ARG "" "" "SOURCES;PRIVATE_LIBS" ${ARGN})
  set(target scandiff_plugin_${NAME})
  add_library(${target} STATIC ${ARG_SOURCES})
  target_include_directories(${target} PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)
  target_link_libraries(${target} PUBLIC scandiff_plugin_api PRIVATE ${ARG_PRIVATE_LIBS})
  set_property(GLOBAL APPEND PROPERTY SCANDIFF_PLUGINS ${NAME})
endfunction()

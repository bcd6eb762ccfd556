# The negative control of core_layers.cmake: a copy of core with one back-edge planted (scene
# including a collision header) must fail the check and name the file; a check that passes it
# checks nothing.
#   cmake -DCORE_DIR=path/to/core -DWORK_DIR=scratch -P core_layers_control.cmake
cmake_minimum_required(VERSION 3.20)
file(REMOVE_RECURSE ${WORK_DIR})
file(COPY ${CORE_DIR}/ DESTINATION ${WORK_DIR}/core)
set(planted ${WORK_DIR}/core/scene/scene_topology.hpp)
if(NOT EXISTS ${planted})
  message(FATAL_ERROR "core_layers_control.cmake: ${planted} is missing: plant the edge elsewhere")
endif()
file(APPEND ${planted} "#include \"core/collision/contact.hpp\"\n")
execute_process(
  COMMAND ${CMAKE_COMMAND} -DCORE_DIR=${WORK_DIR}/core -P ${CMAKE_CURRENT_LIST_DIR}/core_layers.cmake
  RESULT_VARIABLE result OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(result EQUAL 0)
  message(FATAL_ERROR "core_layers.cmake passed a scene header that includes a collision one")
endif()
if(NOT err MATCHES "core/scene/scene_topology.hpp \\(scene\\) includes core/collision/contact.hpp")
  message(FATAL_ERROR "core_layers.cmake failed without naming the planted edge:\n${err}")
endif()
file(REMOVE_RECURSE ${WORK_DIR})
message(STATUS "core_layers.cmake fails on a planted back-edge and names it")

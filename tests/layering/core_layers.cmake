# The layers inside softbake::core, which is one library, so the include-path probes of
# CMakeLists.txt cannot see them: every #include "core/..." of every file under CORE_DIR is checked
# against what its folder may use, and the first back-edge fails with the file, the line and the
# rule it breaks.
#
#   base  <-  mesh  <-  scene  <-  dynamics     <-  top
#                         ^-----  broad_phase  <-  collision  <-  top
#
# base is core's own files but the simulator's (types, errors, text, the parallel helpers, the
# stage timer); top is the simulator and its checkpoint, which see everything.
#   cmake -DCORE_DIR=path/to/core -P core_layers.cmake
cmake_minimum_required(VERSION 3.20)
if(NOT CORE_DIR)
  message(FATAL_ERROR "core_layers.cmake: set CORE_DIR to the core folder")
endif()

set(layers base mesh scene broad_phase dynamics collision top)
set(sees_base base)
set(sees_mesh base mesh)
set(sees_scene base mesh scene)
set(sees_broad_phase base mesh scene broad_phase)
set(sees_dynamics base mesh scene dynamics)
set(sees_collision base mesh scene broad_phase collision)
set(sees_top ${layers})
set(top_files simulator checkpoint)

# The layer of a path relative to core/: its folder, or base or top for a file at the root.
function(layer_of relative out)
  if(relative MATCHES "^([a-z_]+)/")
    set(layer ${CMAKE_MATCH_1})
    if(NOT layer IN_LIST layers)
      message(FATAL_ERROR "core_layers.cmake: core/${relative} is in folder '${layer}', which is "
                          "no layer: add it to the layers of tests/layering/core_layers.cmake")
    endif()
  else()
    get_filename_component(stem ${relative} NAME_WE)
    if(stem IN_LIST top_files)
      set(layer top)
    else()
      set(layer base)
    endif()
  endif()
  set(${out} ${layer} PARENT_SCOPE)
endfunction()

file(GLOB_RECURSE sources RELATIVE ${CORE_DIR} ${CORE_DIR}/*.hpp ${CORE_DIR}/*.cpp)
list(SORT sources)
list(LENGTH sources count)
if(count EQUAL 0)
  message(FATAL_ERROR "core_layers.cmake: no sources under ${CORE_DIR}")
endif()
set(checked 0)
set(broken "")
foreach(source ${sources})
  layer_of(${source} from)
  file(STRINGS ${CORE_DIR}/${source} lines REGEX "^[ \t]*#[ \t]*include[ \t]+\"core/")
  foreach(line ${lines})
    string(REGEX REPLACE "^[ \t]*#[ \t]*include[ \t]+\"core/([^\"]+)\".*" "\\1" target "${line}")
    layer_of(${target} to)
    math(EXPR checked "${checked} + 1")
    if(NOT to IN_LIST sees_${from})
      string(REPLACE ";" ", " allowed "${sees_${from}}")
      string(APPEND broken "  core/${source} (${from}) includes core/${target} (${to}): ${from} "
                           "may use ${allowed}\n")
    endif()
  endforeach()
endforeach()
if(broken)
  message(FATAL_ERROR "core's layers are broken:\n${broken}")
endif()
message(STATUS "core layers: ${checked} includes in ${count} files, none against the layers")

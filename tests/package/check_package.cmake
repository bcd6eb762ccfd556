# ctest's package_consumer: installs the build into a temporary prefix with `cmake --install`,
# configures the consumer project beside this file against that prefix alone, builds it, runs it
# and checks what it prints; then runs the installed `softbake` and, when the build has the Python
# module, imports the installed module. Any step that fails fails the test.
#   cmake -DBUILD_DIR=… -DCONSUMER_DIR=… -DWORK_DIR=… -DGENERATOR=… -DCXX=… [-DCONFIG=…]
#         [-DPYTHON=…] -P check_package.cmake
foreach(variable BUILD_DIR CONSUMER_DIR WORK_DIR GENERATOR CXX)
  if(NOT DEFINED ${variable})
    message(FATAL_ERROR "check_package.cmake needs -D${variable}=…")
  endif()
endforeach()
if(NOT CONFIG)
  set(CONFIG Release)
endif()
set(prefix ${WORK_DIR}/prefix)
set(consumer_build ${WORK_DIR}/build)
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})

# Runs one step; stops the test with its output when it fails. `output` gets what it printed.
function(step name)
  string(TIMESTAMP start "%s")
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE result OUTPUT_VARIABLE out ERROR_VARIABLE out)
  string(TIMESTAMP end "%s")
  math(EXPR seconds "${end} - ${start}")
  if(NOT result EQUAL 0)
    list(JOIN ARGN " " command)
    message(FATAL_ERROR "package: ${name} failed (${result}): ${command}\n${out}")
  endif()
  message(STATUS "package: ${name}: ok (${seconds} s)")
  set(output "${out}" PARENT_SCOPE)
endfunction()

step("install" ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix} --config ${CONFIG})
foreach(file bin/softbake include/softbake/core/simulator.hpp include/softbake/bake/run_bake.hpp
             share/doc/softbake/LICENSE share/doc/softbake/THIRD_PARTY.md)
  if(NOT EXISTS ${prefix}/${file})
    message(FATAL_ERROR "package: the install has no ${file}")
  endif()
endforeach()
file(GLOB_RECURSE configs ${prefix}/*/softbakeConfig.cmake)
file(GLOB_RECURSE libraries ${prefix}/*/libsoftbake_core.a)
if(NOT configs OR NOT libraries)
  message(FATAL_ERROR "package: the install has no softbakeConfig.cmake or libsoftbake_core.a")
endif()

# The prefix is all it may find: no package registry, and the consumer must say it found it there.
step("configure the consumer" ${CMAKE_COMMAND} -S ${CONSUMER_DIR} -B ${consumer_build}
     -G "${GENERATOR}" -DCMAKE_BUILD_TYPE=${CONFIG} -DCMAKE_CXX_COMPILER=${CXX}
     -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF)
string(FIND "${output}" "from ${prefix}/" found)
string(FIND "${output}" "command ${prefix}/bin/softbake" command)
if(found EQUAL -1 OR command EQUAL -1)
  message(FATAL_ERROR "package: the consumer did not find softbake in ${prefix}:\n${output}")
endif()
step("build the consumer" ${CMAKE_COMMAND} --build ${consumer_build} --config ${CONFIG})

foreach(program consumer_core consumer_all)
  set(binary ${consumer_build}/${program})
  if(NOT EXISTS ${binary})
    set(binary ${consumer_build}/${CONFIG}/${program})  # multi-configuration generators
  endif()
  step("run ${program}" ${binary})
  if(NOT output MATCHES "softbake package consumer: 162 particles, frame 24, [0-9]+ substeps, centre from 1.000 m to 0\\.[0-9]+ m, lowest point")
    message(FATAL_ERROR "package: ${program} printed something else:\n${output}")
  endif()
  message(STATUS "package: ${output}")
endforeach()

step("run the installed softbake" ${prefix}/bin/softbake --version)
message(STATUS "package: ${output}")

if(PYTHON)
  file(GLOB_RECURSE modules ${prefix}/lib/*/softbake.cpython-*.so)
  list(LENGTH modules count)
  if(NOT count EQUAL 1)
    message(FATAL_ERROR "package: expected one installed Python module, found: ${modules}")
  endif()
  get_filename_component(site ${modules} DIRECTORY)
  # One statement a line: a ';' would split the command into several arguments.
  string(JOIN "\n" script
         "import softbake"
         "assert softbake.__file__.startswith('${site}/'), softbake.__file__"
         "simulation = softbake.Simulation('default')"
         "simulation.advance(2)"
         "print('softbake', softbake.__version__, 'from', softbake.__file__, simulation)")
  step("import the installed Python module"
       ${CMAKE_COMMAND} -E env PYTHONPATH=${site} PYTHONDONTWRITEBYTECODE=1 ${PYTHON} -c "${script}")
  if(NOT output MATCHES "at frame 3 of 240")
    message(FATAL_ERROR "package: the installed Python module printed something else:\n${output}")
  endif()
  message(STATUS "package: ${output}")
endif()

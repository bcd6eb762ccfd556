# `cmake --install BUILD --prefix P` (included last by the top-level CMakeLists.txt):
#
#   P/bin/softbake                                   the command (its rule is in cli/)
#   P/lib/libsoftbake_{core,output,…}.a              the static libraries
#   P/include/softbake/{core,output,…}/*.hpp         their headers: #include "core/simulator.hpp"
#   P/lib/cmake/softbake/softbakeConfig.cmake …      find_package(softbake), softbake::core …
#   P/lib/python3/dist-packages/softbake.*.so        the Python module (SOFTBAKE_PYTHON_INSTALL_DIR)
#   P/share/doc/softbake/{LICENSE,THIRD_PARTY.md}
#
# Each library is a component of the package with an export file of its own, so a consumer that
# asks for `COMPONENTS core` needs Eigen and TBB only, not assimp, OpenVDB or EGL; without
# COMPONENTS it gets them all. install(TARGETS) reaches targets of other folders (CMake ≥ 3.13).
include(CMakePackageConfigHelpers)

set(SOFTBAKE_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/softbake CACHE STRING
    "Where the CMake package files go, relative to the prefix")
set(softbake_install_includedir ${CMAKE_INSTALL_INCLUDEDIR}/softbake)

# In the order they depend on each other; softbakeConfig.cmake knows the same order.
set(softbake_components core output importers exporters render bake cli)

# Every library links this warnings target privately; a static library's private links are still
# named in what it exports (as link-only), so it travels in the core set. It carries no flags to a
# consumer: link-only usage brings no compile options.
install(TARGETS softbake_warnings EXPORT softbake-core)
set_target_properties(softbake_warnings PROPERTIES EXPORT_NAME warnings)

foreach(component IN LISTS softbake_components)
  set(target softbake_${component})
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${component})
  install(TARGETS ${target} EXPORT softbake-${component}
          ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT development)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${component}/
          DESTINATION ${softbake_install_includedir}/${component} COMPONENT development
          FILES_MATCHING PATTERN "*.hpp")
  install(EXPORT softbake-${component} NAMESPACE softbake:: DESTINATION ${SOFTBAKE_INSTALL_CMAKEDIR}
          FILE softbake-${component}-targets.cmake COMPONENT development)
endforeach()

# Libraries compiled with a sanitizer need its runtime in whatever links them.
set(softbake_sanitizer_link_options "")
if(SOFTBAKE_SANITIZE OR SOFTBAKE_FUZZ)
  list(APPEND softbake_sanitizer_link_options -fsanitize=address,undefined)
endif()
if(SOFTBAKE_TSAN)
  list(APPEND softbake_sanitizer_link_options -fsanitize=thread)
endif()
if(softbake_sanitizer_link_options)
  target_link_options(softbake_core INTERFACE
                      $<INSTALL_INTERFACE:${softbake_sanitizer_link_options}>)
endif()

# Debian's FindOpenVDB (and the FindTBB beside it, which the build uses for TBB too) live outside
# CMake's module path; the package looks where this build found them.
find_file(softbake_find_openvdb FindOpenVDB.cmake PATHS ${CMAKE_MODULE_PATH} NO_DEFAULT_PATH)
mark_as_advanced(softbake_find_openvdb)
if(softbake_find_openvdb)
  get_filename_component(SOFTBAKE_OPENVDB_MODULE_DIR ${softbake_find_openvdb} DIRECTORY)
else()
  set(SOFTBAKE_OPENVDB_MODULE_DIR "")
endif()

configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/softbakeConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/package/softbakeConfig.cmake
                              INSTALL_DESTINATION ${SOFTBAKE_INSTALL_CMAKEDIR}
                              PATH_VARS CMAKE_INSTALL_BINDIR)
# 0.x: a minor version may change the API, so only the same minor version is compatible.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/package/softbakeConfigVersion.cmake
                                 VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/package/softbakeConfig.cmake
              ${PROJECT_BINARY_DIR}/package/softbakeConfigVersion.cmake
        DESTINATION ${SOFTBAKE_INSTALL_CMAKEDIR} COMPONENT development)

install(FILES ${PROJECT_SOURCE_DIR}/LICENSE ${PROJECT_SOURCE_DIR}/THIRD_PARTY.md
        DESTINATION ${CMAKE_INSTALL_DOCDIR})

if(TARGET softbake_python)
  install(TARGETS softbake_python LIBRARY DESTINATION ${SOFTBAKE_PYTHON_INSTALL_DIR} COMPONENT python)
endif()

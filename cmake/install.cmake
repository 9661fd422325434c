# install() rules and the exported CMake package: after `cmake --install build --prefix P`,
# a project configured with -DCMAKE_PREFIX_PATH=P does
#   find_package(curvestereo REQUIRED)
#   target_link_libraries(app PRIVATE curvestereo::curvestereo)
# (tests/downstream is one). Installed: the static libraries of every layer, the public
# headers (core/include/curvestereo, and curvestereo/cuda.hpp with CUDA), the targets and
# curvestereoConfig.cmake, which finds the dependencies the static libraries carry.
include(CMakePackageConfigHelpers)

set(CS_INSTALL_TARGETS curvestereo curvestereo_core curvestereo_cpu)
set(CS_CONFIG_HAVE_CUDA OFF)
if(TARGET curvestereo_cuda)
  list(APPEND CS_INSTALL_TARGETS curvestereo_cuda)
  set(CS_CONFIG_HAVE_CUDA ON)
endif()
if(TARGET curvestereo_vulkan)
  list(APPEND CS_INSTALL_TARGETS curvestereo_vulkan)
endif()
# curvestereo::curvestereo on top; the layers as curvestereo::core, ::cpu, ::cuda, ::vulkan.
set_target_properties(curvestereo_core PROPERTIES EXPORT_NAME core)
set_target_properties(curvestereo_cpu PROPERTIES EXPORT_NAME cpu)
if(TARGET curvestereo_cuda)
  set_target_properties(curvestereo_cuda PROPERTIES EXPORT_NAME cuda)
endif()
if(TARGET curvestereo_vulkan)
  set_target_properties(curvestereo_vulkan PROPERTIES EXPORT_NAME vulkan)
endif()

set(CS_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/curvestereo)
install(TARGETS ${CS_INSTALL_TARGETS} EXPORT curvestereoTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})  # includes: curvestereo_core's INSTALL_INTERFACE
install(DIRECTORY ${CMAKE_SOURCE_DIR}/core/include/curvestereo DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
        FILES_MATCHING PATTERN "*.hpp")
if(CS_CONFIG_HAVE_CUDA)
  install(FILES ${CMAKE_SOURCE_DIR}/stereo/include/curvestereo/cuda.hpp
          DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/curvestereo)
endif()
install(EXPORT curvestereoTargets NAMESPACE curvestereo:: DESTINATION ${CS_CMAKE_DIR})

configure_package_config_file(${CMAKE_SOURCE_DIR}/cmake/curvestereoConfig.cmake.in
  ${CMAKE_BINARY_DIR}/curvestereoConfig.cmake INSTALL_DESTINATION ${CS_CMAKE_DIR})
# 0.x: a minor version may break the API.
write_basic_package_version_file(${CMAKE_BINARY_DIR}/curvestereoConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_BINARY_DIR}/curvestereoConfig.cmake ${CMAKE_BINARY_DIR}/curvestereoConfigVersion.cmake
        DESTINATION ${CS_CMAKE_DIR})

# The command line tool.
install(TARGETS curvestereo_cli RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})

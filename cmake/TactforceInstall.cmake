# Installation: `cmake --install build --prefix /usr/local` puts
#   bin/tactforce, bin/tactforce-server
#   include/tactforce/<lib>/*.h           every exported library's public headers
#   include/tactforce/api/version.h       generated (api/CMakeLists.txt)
#   include/tactforce/v1/*.pb.h, *.grpc.pb.h, *.proto   generated code and its sources
#   lib/libtactforce_<lib>.a              io planner estimator inertia sim audit proto api
#   lib/cmake/tactforce/                  tactforceConfig.cmake (+ Version, Targets)
#   lib/pkgconfig/tactforce.pc
#   share/doc/tactforce/LICENSE, README.md
# so that another project can `find_package(tactforce CONFIG REQUIRED)` and
# link tactforce::planner, tactforce::api, ... (or use pkg-config).
# The CLI's own pieces (experiment/, the server library) are not exported.
# Included from the top-level CMakeLists.txt after every library exists.
include(CMakePackageConfigHelpers)

# Library target -> the folder whose include/ holds its public headers.
set(_tactforce_exported
  tactforce_io:io
  tactforce_planner:planner
  tactforce_estimator:estimator
  tactforce_inertia:estimator/inertia
  tactforce_sim:sim
  tactforce_audit:audit
  tactforce_proto:
  tactforce_api:api)

# planner/CMakeLists.txt (owned by the planner work) still names its include
# directory as a plain source path and sets no EXPORT_NAME; both are set here
# so the export is relocatable. A no-op once planner/CMakeLists.txt uses
# $<BUILD_INTERFACE:...>/$<INSTALL_INTERFACE:...> itself.
get_target_property(_planner_includes tactforce_planner INTERFACE_INCLUDE_DIRECTORIES)
if(NOT _planner_includes MATCHES "BUILD_INTERFACE")
  set_property(TARGET tactforce_planner PROPERTY INTERFACE_INCLUDE_DIRECTORIES
    $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/planner/include>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
endif()
get_target_property(_planner_export_name tactforce_planner EXPORT_NAME)
if(NOT _planner_export_name)
  set_target_properties(tactforce_planner PROPERTIES EXPORT_NAME planner)
endif()

set(_tactforce_targets)
foreach(_entry IN LISTS _tactforce_exported)
  string(REPLACE ":" ";" _pair "${_entry}")
  list(GET _pair 0 _target)
  list(APPEND _tactforce_targets ${_target})
  list(LENGTH _pair _n)
  if(_n GREATER 1)
    list(GET _pair 1 _folder)
    install(DIRECTORY ${PROJECT_SOURCE_DIR}/${_folder}/include/
      DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
      COMPONENT tactforce_development
      FILES_MATCHING PATTERN "*.h")
  endif()
endforeach()

install(TARGETS ${_tactforce_targets}
  EXPORT tactforceTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT tactforce_development
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT tactforce_runtime
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT tactforce_runtime)

# Generated headers: tactforce/api/version.h and the protoc output.
get_target_property(_api_binary_dir tactforce_api BINARY_DIR)
install(FILES ${_api_binary_dir}/include/tactforce/api/version.h
  DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/tactforce/api COMPONENT tactforce_development)
get_target_property(_proto_binary_dir tactforce_proto BINARY_DIR)
install(DIRECTORY ${_proto_binary_dir}/gen/tactforce
  DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
  COMPONENT tactforce_development
  FILES_MATCHING PATTERN "*.pb.h")
# The .proto files beside their generated headers, for other languages' stubs.
install(DIRECTORY ${PROJECT_SOURCE_DIR}/proto/tactforce
  DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
  COMPONENT tactforce_development
  FILES_MATCHING PATTERN "*.proto")

install(TARGETS tactforce tactforce-server
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT tactforce_runtime)
install(FILES ${PROJECT_SOURCE_DIR}/LICENSE ${PROJECT_SOURCE_DIR}/README.md
  DESTINATION ${CMAKE_INSTALL_DOCDIR} COMPONENT tactforce_runtime)

# ---- CMake package: find_package(tactforce CONFIG)
set(TACTFORCE_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/tactforce)
install(EXPORT tactforceTargets
  NAMESPACE tactforce::
  FILE tactforceTargets.cmake
  DESTINATION ${TACTFORCE_CMAKE_DIR}
  COMPONENT tactforce_development)
configure_package_config_file(
  ${PROJECT_SOURCE_DIR}/cmake/tactforceConfig.cmake.in
  ${PROJECT_BINARY_DIR}/cmake/tactforceConfig.cmake
  INSTALL_DESTINATION ${TACTFORCE_CMAKE_DIR})
# 0.x: a minor version may break the API, so only the same MAJOR.MINOR matches.
write_basic_package_version_file(
  ${PROJECT_BINARY_DIR}/cmake/tactforceConfigVersion.cmake
  VERSION ${PROJECT_VERSION}
  COMPATIBILITY SameMinorVersion)
install(FILES
  ${PROJECT_BINARY_DIR}/cmake/tactforceConfig.cmake
  ${PROJECT_BINARY_DIR}/cmake/tactforceConfigVersion.cmake
  DESTINATION ${TACTFORCE_CMAKE_DIR}
  COMPONENT tactforce_development)

# ---- pkg-config: tactforce.pc, relocatable (prefix from the file's own place).
file(RELATIVE_PATH TACTFORCE_PC_TO_PREFIX
  /prefix/${CMAKE_INSTALL_LIBDIR}/pkgconfig /prefix)
string(REGEX REPLACE "/$" "" TACTFORCE_PC_TO_PREFIX "${TACTFORCE_PC_TO_PREFIX}")
if(BUILD_SHARED_LIBS)
  # Only what the public headers use; the rest is the shared objects' business.
  set(TACTFORCE_PC_REQUIRES "eigen3 >= 3.4, absl_status, absl_statusor, absl_strings, protobuf, grpc++")
  set(TACTFORCE_PC_REQUIRES_PRIVATE "\nRequires.private: absl_str_format, absl_flat_hash_map, absl_flat_hash_set, ipopt, nlopt, qhull_r, assimp, spdlog, nlohmann_json")
else()
  # Static archives: a consumer links everything they use.
  set(TACTFORCE_PC_REQUIRES "eigen3 >= 3.4, absl_status, absl_statusor, absl_strings, absl_str_format, absl_flat_hash_map, absl_flat_hash_set, protobuf, grpc++, ipopt, nlopt, qhull_r, assimp, spdlog, nlohmann_json")
  set(TACTFORCE_PC_REQUIRES_PRIVATE "")
endif()
configure_file(${PROJECT_SOURCE_DIR}/cmake/tactforce.pc.in
  ${PROJECT_BINARY_DIR}/cmake/tactforce.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/cmake/tactforce.pc
  DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig
  COMPONENT tactforce_development)

# Installs the SDK as the CMake package `plr` (component `sdk`):
#   find_package(plr REQUIRED)                          -> plr::sdk, plr::sdk_support,
#                                                          plr_add_plugin()
#   find_package(plr REQUIRED COMPONENTS testing)       -> also plr::testing (fake kernel),
#     plr::conformance, plr::conformance_runner, plr_add_conformance_test(),
#     plr::host_contract
# Included from sdk/CMakeLists.txt, so generated_headers and schema_files are in scope.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(PLR_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/plr)
set(PLR_SCHEMA_INSTALL_DIR ${CMAKE_INSTALL_DATADIR}/plr/schemas)

set_target_properties(plr_sdk PROPERTIES EXPORT_NAME sdk)
install(TARGETS plr_sdk plr_sdk_support EXPORT plrTargets COMPONENT sdk)
install(DIRECTORY include/plr DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} COMPONENT sdk)
install(FILES ${generated_headers} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/plr/msg COMPONENT sdk)
install(FILES ${schema_files} DESTINATION ${PLR_SCHEMA_INSTALL_DIR} COMPONENT sdk)
install(EXPORT plrTargets NAMESPACE plr:: DESTINATION ${PLR_INSTALL_CMAKEDIR} COMPONENT sdk)

set(cmake_files ${CMAKE_CURRENT_SOURCE_DIR}/cmake/PlrPlugin.cmake)
if(TARGET plr_conformance)
  install(TARGETS plr_sdk_testing plr_sdk_conformance plr_conformance plr_host_contract
          EXPORT plrTestingTargets
          COMPONENT sdk)
  install(DIRECTORY testing/include/plr/testing DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/plr
          COMPONENT sdk)
  install(EXPORT plrTestingTargets NAMESPACE plr:: DESTINATION ${PLR_INSTALL_CMAKEDIR}
          COMPONENT sdk)
  list(APPEND cmake_files ${CMAKE_CURRENT_SOURCE_DIR}/cmake/PlrTesting.cmake)
endif()

configure_package_config_file(cmake/plrConfig.cmake.in ${CMAKE_CURRENT_BINARY_DIR}/plrConfig.cmake
  INSTALL_DESTINATION ${PLR_INSTALL_CMAKEDIR}
  PATH_VARS PLR_SCHEMA_INSTALL_DIR)
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/plrConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/plrConfig.cmake
              ${CMAKE_CURRENT_BINARY_DIR}/plrConfigVersion.cmake ${cmake_files}
        DESTINATION ${PLR_INSTALL_CMAKEDIR} COMPONENT sdk)

# Tests of the kernel front end (config, plug-in loader). Included from this
# folder's CMakeLists.txt.

# Plug-ins for the loader tests, each broken in one way, in a folder of their
# own so that no real search path ever holds them.
set(broken_plugin_dir ${CMAKE_CURRENT_BINARY_DIR}/broken_plugins)
function(add_test_plugin target file_name)
  add_library(${target} MODULE ${CMAKE_CURRENT_LIST_DIR}/broken_plugins/test_plugin.c)
  target_include_directories(${target} PRIVATE ${PROJECT_SOURCE_DIR}/sdk/include)
  target_compile_definitions(${target} PRIVATE ${ARGN})
  set_target_properties(${target} PROPERTIES
    PREFIX ""
    OUTPUT_NAME ${file_name}
    C_VISIBILITY_PRESET hidden
    LIBRARY_OUTPUT_DIRECTORY ${broken_plugin_dir})
endfunction()
add_test_plugin(kernel_test_plugin_valid valid_plugin TEST_PLUGIN_NAME="valid_plugin")
add_test_plugin(kernel_test_plugin_old_abi old_abi TEST_PLUGIN_NAME="old_abi" TEST_PLUGIN_ABI_MAJOR=0)
add_test_plugin(kernel_test_plugin_no_entry no_entry TEST_PLUGIN_NAME="no_entry" TEST_PLUGIN_NO_ENTRY)
add_test_plugin(kernel_test_plugin_misnamed misnamed TEST_PLUGIN_NAME="another_name")
add_test_plugin(kernel_test_plugin_unresolved unresolved TEST_PLUGIN_NAME="unresolved" TEST_PLUGIN_UNRESOLVED)

add_executable(kernel_config_test ${CMAKE_CURRENT_LIST_DIR}/config_test.cpp)
target_link_libraries(kernel_config_test PRIVATE plr_kernel_frontend GTest::gtest_main plr_warnings)
gtest_discover_tests(kernel_config_test)

add_executable(kernel_loader_test ${CMAKE_CURRENT_LIST_DIR}/plugin_loader_test.cpp)
target_link_libraries(kernel_loader_test PRIVATE plr_kernel_frontend GTest::gtest_main plr_warnings)
target_compile_definitions(kernel_loader_test PRIVATE
  PLR_BROKEN_PLUGIN_DIR="${broken_plugin_dir}"
  PLR_DEMO_PLUGIN_DIR="$<TARGET_FILE_DIR:demo_counter>")
add_dependencies(kernel_loader_test
  kernel_test_plugin_valid kernel_test_plugin_old_abi kernel_test_plugin_no_entry
  kernel_test_plugin_misnamed kernel_test_plugin_unresolved demo_counter demo_doubler)
gtest_discover_tests(kernel_loader_test)

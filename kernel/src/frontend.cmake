# The kernel's front end: config parsing and plug-in loading. Included from
# kernel/CMakeLists.txt; plr_kernel links it.
add_library(plr_kernel_frontend STATIC
  ${CMAKE_CURRENT_LIST_DIR}/config.cpp
  ${CMAKE_CURRENT_LIST_DIR}/plugin_loader.cpp)
target_include_directories(plr_kernel_frontend PUBLIC ${CMAKE_CURRENT_LIST_DIR})
target_link_libraries(plr_kernel_frontend
  PUBLIC plr::sdk nlohmann_json::nlohmann_json
  PRIVATE yaml-cpp ${CMAKE_DL_LIBS} plr_warnings)

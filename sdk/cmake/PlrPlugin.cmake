# plr_add_plugin(name SOURCES a.cpp b.cpp [LIBRARIES lib...])
# Builds a plug-in module <name>.so that the kernel can load. Works in the PLR
# tree and from an installed package (find_package(plr)).
function(plr_add_plugin name)
  cmake_parse_arguments(ARG "" "" "SOURCES;LIBRARIES" ${ARGN})
  if(NOT ARG_SOURCES)
    message(FATAL_ERROR "plr_add_plugin(${name}): SOURCES is required")
  endif()
  add_library(${name} MODULE ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE plr::sdk ${ARG_LIBRARIES})
  if(TARGET plr_warnings)
    target_link_libraries(${name} PRIVATE plr_warnings)
  endif()
  set(out ${CMAKE_CURRENT_BINARY_DIR})
  if(PLR_PLUGIN_OUTPUT_DIRECTORY)
    set(out ${PLR_PLUGIN_OUTPUT_DIRECTORY})
  endif()
  set_target_properties(${name} PROPERTIES
    PREFIX ""
    CXX_VISIBILITY_PRESET hidden
    VISIBILITY_INLINES_HIDDEN ON
    LIBRARY_OUTPUT_DIRECTORY ${out})
  # Catch unresolved symbols at link time, not at dlopen time (sanitizer
  # runtimes resolve only at load time, so not there).
  if(NOT PLR_ASAN AND NOT PLR_TSAN)
    target_link_options(${name} PRIVATE -Wl,--no-undefined)
  endif()
endfunction()

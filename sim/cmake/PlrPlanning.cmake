# plr_add_planner_conformance_test(<plugin target> [PARAMS <json object>] [NAME <test name>])
# Adds a ctest (default name planner_conformance.<target>) that runs the SDK's
# conformance suite and the planner conformance suite
# (plr/planning/testing/planner_conformance.hpp) on a planner plug-in. Works
# in the PLR tree and from an installed package
# (find_package(plr COMPONENTS planning)).
function(plr_add_planner_conformance_test plugin)
  cmake_parse_arguments(ARG "" "PARAMS;NAME" "" ${ARGN})
  if(NOT TARGET ${plugin})
    message(FATAL_ERROR "plr_add_planner_conformance_test(${plugin}): no such target")
  endif()
  if(ARG_UNPARSED_ARGUMENTS)
    message(FATAL_ERROR
      "plr_add_planner_conformance_test(${plugin}): unexpected arguments ${ARG_UNPARSED_ARGUMENTS}")
  endif()
  if(NOT DEFINED ARG_PARAMS)
    set(ARG_PARAMS "{}")
  endif()
  if(NOT ARG_NAME)
    set(ARG_NAME planner_conformance.${plugin})
  endif()
  if(TARGET plr::planner_conformance_runner)
    set(runner plr::planner_conformance_runner)
  else()
    set(runner plr_planner_conformance)
  endif()
  add_test(NAME ${ARG_NAME}
           COMMAND $<TARGET_FILE:${runner}> $<TARGET_FILE:${plugin}> "${ARG_PARAMS}")
  set_tests_properties(${ARG_NAME} PROPERTIES LABELS conformance TIMEOUT 300)
endfunction()

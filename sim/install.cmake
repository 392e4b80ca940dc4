# Installs what a planner plug-in builds on as the `planning` component of the
# package `plr` (find_package(plr REQUIRED COMPONENTS planning)):
#   plr::planning                 the planner contract, query types, search core,
#                                 lattice planner, robot model and collision checking
#   plr::planning_testing         the planner conformance suite
#   plr::planner_conformance_runner, plr_add_planner_conformance_test()
# and the shipped robot (share/plr/robots), found relative to the libraries.
include(GNUInstallDirs)
set(PLR_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/plr)

set(planning_targets plr_sim_common plr_sim_world plr_sim_robot plr_search plr_planning)
foreach(t IN LISTS planning_targets)
  string(REGEX REPLACE "^plr_" "" name ${t})
  set_target_properties(${t} PROPERTIES EXPORT_NAME ${name})
endforeach()
install(TARGETS ${planning_targets} EXPORT plrPlanningTargets COMPONENT sdk)
# (plr_planning_ompl is not in the package, nor is its header.)
foreach(lib IN ITEMS common world robot search planning)
  install(DIRECTORY ${lib}/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} COMPONENT sdk
          PATTERN ompl_planner.hpp EXCLUDE)
endforeach()
foreach(file IN LISTS PLR_SHIPPED_DATA)
  get_filename_component(dir ${file} DIRECTORY)
  install(FILES ${file} DESTINATION ${CMAKE_INSTALL_DATADIR}/plr/${dir} COMPONENT sdk)
endforeach()
install(EXPORT plrPlanningTargets NAMESPACE plr:: DESTINATION ${PLR_INSTALL_CMAKEDIR} COMPONENT sdk)

if(TARGET plr_planning_testing)
  set_target_properties(plr_planning_testing PROPERTIES EXPORT_NAME planning_testing)
  set_target_properties(plr_planner_conformance PROPERTIES EXPORT_NAME planner_conformance_runner)
  install(TARGETS plr_planning_testing plr_planner_conformance EXPORT plrPlanningTestingTargets
          COMPONENT sdk)
  install(EXPORT plrPlanningTestingTargets NAMESPACE plr:: DESTINATION ${PLR_INSTALL_CMAKEDIR}
          COMPONENT sdk)
  install(FILES cmake/PlrPlanning.cmake DESTINATION ${PLR_INSTALL_CMAKEDIR} COMPONENT sdk)
endif()

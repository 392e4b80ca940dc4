cmake_minimum_required(VERSION 3.25)
# The dependency rules catch a lower sim/ library reaching up: on a small
# tree of their own, they hold; with the physics library including an
# actions header, or linking the actions library, they fail naming it. They
# also fail on a library under sim/ without a layer and on a plug-in's
# sources on another target's include path.
# cmake -DRULES=<dependency_rules.cmake> -DWORK_DIR=<scratch folder> -P dependency_rules_violations.cmake

# A tree with the physics and actions libraries, actions on top of physics.
function(write_tree root)
  file(REMOVE_RECURSE ${root})
  file(WRITE ${root}/sim/physics/include/plr/sim/physics.hpp "#pragma once\n")
  file(WRITE ${root}/sim/physics/simulation.cpp "#include \"plr/sim/physics.hpp\"\n")
  file(WRITE ${root}/sim/actions/include/plr/actions/rig.hpp "#pragma once\n")
  file(WRITE ${root}/sim/actions/rig.cpp
    "#include \"plr/actions/rig.hpp\"\n#include \"plr/sim/physics.hpp\"\n")
endfunction()

# Runs the rules on <root> with <graph> as the link graph; fails unless they
# pass (expect "") or fail with a message matching the regex <expect>.
function(check name root graph expect)
  file(WRITE ${root}/link_graph.txt "${graph}")
  execute_process(COMMAND ${CMAKE_COMMAND} -DROOT=${root} -DLINK_GRAPH=${root}/link_graph.txt
                          -P ${RULES}
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(expect STREQUAL "")
    if(NOT rc EQUAL 0)
      message(FATAL_ERROR "${name}: the rules fail on a tree that keeps them:\n${out}")
    endif()
  elseif(rc EQUAL 0)
    message(FATAL_ERROR "${name}: the rules pass on a tree that breaks them:\n${out}")
  endif()
  # CMake wraps a message's long lines.
  string(REPLACE " " "[ \n]+" expect_wrapped "${expect}")
  if(NOT expect STREQUAL "" AND NOT out MATCHES "${expect_wrapped}")
    message(FATAL_ERROR "${name}: the rules fail, but not naming '${expect}':\n${out}")
  endif()
  message(STATUS "${name}: ok")
endfunction()

set(graph_ok "target plr_sim_physics sim/physics
target plr_sim_actions sim/actions
link plr_sim_actions plr_sim_physics
")
set(tree ${WORK_DIR}/tree)

write_tree(${tree})
check("layered tree" ${tree} "${graph_ok}" "")

file(APPEND ${tree}/sim/physics/simulation.cpp "#include \"plr/actions/rig.hpp\"\n")
check("physics includes an actions header" ${tree} "${graph_ok}"
      "sim/physics/simulation.cpp: includes plr/actions/rig.hpp \\(sim/physics is not above sim/actions\\)")

write_tree(${tree})
check("physics links actions" ${tree} "${graph_ok}link plr_sim_physics plr_sim_actions\n"
      "target plr_sim_physics \\(sim/physics\\) links plr_sim_actions \\(sim/actions\\)")

file(WRITE ${tree}/sim/unlisted/thing.cpp "#include \"plr/sim/physics.hpp\"\n")
check("a library without a layer" ${tree} "${graph_ok}"
      "sim/unlisted has no line in the sim layers")

# A plug-in's sources on another target's include path, named or exported
# (as the POMDP solver's were when it lived in the strategy generator).
write_tree(${tree})
check("a plug-in's folder named" ${tree} "${graph_ok}target fuzz_cassandra tests/fuzz
include fuzz_cassandra plugins/strategy_generator/src
" "target fuzz_cassandra \\(tests/fuzz\\) has plugins/strategy_generator/src on its include path")
check("a plug-in's folder exported" ${tree} "${graph_ok}target plr_pomdp plugins/strategy_generator
export plr_pomdp plugins/strategy_generator/src
target bench_pomdp tests/bench/pomdp
link bench_pomdp plr_pomdp
" "target bench_pomdp \\(tests/bench/pomdp\\) links plr_pomdp, which puts plugins/strategy_generator/src")

file(REMOVE_RECURSE ${WORK_DIR})

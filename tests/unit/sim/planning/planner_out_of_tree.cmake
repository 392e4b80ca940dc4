# Installs the SDK with its planning component into a fresh prefix, builds
# the breadth-first planner in planner_bfs/ against it as an outside project
# would (find_package(plr COMPONENTS planning testing)), and runs the planner
# conformance suite on it.
# cmake -DBUILD_DIR=... -DPROJECT_DIR=... -DWORK_DIR=... -DGENERATOR=... -DCXX=...
#       -DSANITIZE=<flags or empty> -DSANITIZE_OPTION=<PLR_ASAN, PLR_TSAN or empty>
#       -P planner_out_of_tree.cmake
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}\n${out}")
  endif()
  message(STATUS "ok: ${ARGN}")
endfunction()

file(REMOVE_RECURSE ${WORK_DIR})
set(prefix ${WORK_DIR}/prefix)
run(${CMAKE_COMMAND} --install ${BUILD_DIR} --component sdk --prefix ${prefix})

set(flags)
if(SANITIZE)
  set(flags -D${SANITIZE_OPTION}=ON "-DCMAKE_CXX_FLAGS=${SANITIZE}" "-DCMAKE_EXE_LINKER_FLAGS=${SANITIZE}"
            "-DCMAKE_MODULE_LINKER_FLAGS=${SANITIZE}")
endif()
run(${CMAKE_COMMAND} -S ${PROJECT_DIR} -B ${WORK_DIR}/build -G ${GENERATOR}
    -DCMAKE_CXX_COMPILER=${CXX} -DCMAKE_BUILD_TYPE= -DCMAKE_PREFIX_PATH=${prefix} ${flags})
run(${CMAKE_COMMAND} --build ${WORK_DIR}/build -j 2)
execute_process(COMMAND ${CMAKE_CTEST_COMMAND} --test-dir ${WORK_DIR}/build --output-on-failure
                RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "the out-of-tree planner failed the planner conformance suite")
endif()
file(REMOVE_RECURSE ${WORK_DIR})

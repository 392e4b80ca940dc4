# Installs the SDK component of a built PLR tree into a fresh prefix, builds
# sdk/template against it as an outside project would, and runs its tests
# (fake-kernel unit test and the conformance suite).
# cmake -DBUILD_DIR=... -DTEMPLATE_DIR=... -DWORK_DIR=... -DGENERATOR=... -DCXX=...
#       -DSANITIZE=<flags or empty> -DSANITIZE_OPTION=<PLR_ASAN, PLR_TSAN or empty>
#       -P template_out_of_tree.cmake
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

# The package must stand alone: nothing in it may point back into the tree.
file(GLOB_RECURSE cmake_files ${prefix}/*.cmake)
get_filename_component(source_dir ${TEMPLATE_DIR}/../.. ABSOLUTE)
foreach(f IN LISTS cmake_files)
  file(READ ${f} text)
  string(FIND "${text}" "${source_dir}/" at)
  if(NOT at EQUAL -1)
    message(FATAL_ERROR "${f} refers to the source tree ${source_dir}")
  endif()
endforeach()

set(flags)
if(SANITIZE)
  set(flags -D${SANITIZE_OPTION}=ON "-DCMAKE_CXX_FLAGS=${SANITIZE}" "-DCMAKE_EXE_LINKER_FLAGS=${SANITIZE}"
            "-DCMAKE_MODULE_LINKER_FLAGS=${SANITIZE}")
endif()
run(${CMAKE_COMMAND} -S ${TEMPLATE_DIR} -B ${WORK_DIR}/build -G ${GENERATOR}
    # No build type: unoptimised, the quickest to compile.
    -DCMAKE_CXX_COMPILER=${CXX} -DCMAKE_BUILD_TYPE= -DCMAKE_PREFIX_PATH=${prefix}
    ${flags})
run(${CMAKE_COMMAND} --build ${WORK_DIR}/build -j 2)
execute_process(COMMAND ${CMAKE_CTEST_COMMAND} --test-dir ${WORK_DIR}/build --output-on-failure
                RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "the template's tests failed")
endif()
file(REMOVE_RECURSE ${WORK_DIR})

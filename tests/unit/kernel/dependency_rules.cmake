cmake_minimum_required(VERSION 3.25)
# Who may depend on whom (docs/architecture.md), checked on the includes of
# every file and on the link graph of every target:
#   kernel/           -> sdk/
#   sdk/              -> nothing of ours
#   sim/<lib>/        -> sdk/ and the sim/ libraries below it (the layers below)
#   plugins/<name>/   -> sdk/, sim/ (never another plug-in, never the kernel)
# Fails naming each offending file with the include, or target.
# cmake -DROOT=<source tree> -DLINK_GRAPH=<link_graph.txt> -P dependency_rules.cmake

# The layers of sim/, lowest first: a library, then the sim/ libraries it
# builds on directly (it may also use everything those build on). A library
# under sim/ needs its line here; a library above another may use it, never
# the other way round.
set(sim_layers
  "common"
  "world       common"
  "robot       world"
  "physics     robot"
  "semantic    world"
  "search"
  "planning    robot search"
  "jobs        common"
  "actions     physics planning semantic jobs"
  "episode     actions"
  "chooser     episode"
  "evaluation  chooser episode"
  "pomdp"
  "ros2")

# below_<lib>: every sim/ library <lib> may depend on (the closure of its line).
set(sim_libraries "")
foreach(line IN LISTS sim_layers)
  string(REGEX MATCHALL "[^ ]+" words "${line}")
  list(POP_FRONT words lib)
  set(below "")
  foreach(dep IN LISTS words)
    if(NOT dep IN_LIST sim_libraries)
      message(FATAL_ERROR "sim layer '${lib}' builds on '${dep}', which is not listed before it")
    endif()
    list(APPEND below ${dep} ${below_${dep}})
  endforeach()
  list(REMOVE_DUPLICATES below)
  set(below_${lib} ${below})
  list(APPEND sim_libraries ${lib})
endforeach()

# The area a path (relative to ROOT) belongs to: kernel, sdk, sim/<lib>, sim
# (the folder's top), plugins/<name>, or "" for what the rules do not cover
# (tests, the top).
function(area_of path out)
  if(path MATCHES "^sim/([^/]+)(/|$)")
    set(${out} sim/${CMAKE_MATCH_1} PARENT_SCOPE)
  elseif(path MATCHES "^(kernel|sdk|sim)(/|$)")
    set(${out} ${CMAKE_MATCH_1} PARENT_SCOPE)
  elseif(path MATCHES "^plugins/([^/]+)")
    set(${out} plugins/${CMAKE_MATCH_1} PARENT_SCOPE)
  else()
    set(${out} "" PARENT_SCOPE)
  endif()
endfunction()

# Whether `from` may depend on `to` (areas as above; "" is the top folder,
# whose helpers such as plr_warnings every area may use). `why` says why not.
function(allowed from to out why)
  set(ok FALSE)
  set(reason "${from} may not depend on ${to}")
  if(to STREQUAL "" OR to STREQUAL from OR (NOT from STREQUAL "sdk" AND to STREQUAL "sdk"))
    set(ok TRUE)
  elseif(from MATCHES "^plugins/" AND to MATCHES "^sim(/|$)")
    set(ok TRUE)
  elseif(from MATCHES "^sim(/|$)" AND to MATCHES "^sim(/|$)")
    string(REGEX REPLACE "^sim/?" "" from_lib "${from}")
    string(REGEX REPLACE "^sim/?" "" to_lib "${to}")
    if(from_lib STREQUAL "" OR to_lib STREQUAL "")
      set(ok TRUE)
    elseif(NOT from_lib IN_LIST sim_libraries)
      set(reason "${from} has no line in the sim layers (dependency_rules.cmake)")
    elseif(to_lib IN_LIST below_${from_lib})
      set(ok TRUE)
    else()
      set(reason "${from} is not above ${to}")
    endif()
  endif()
  set(${out} ${ok} PARENT_SCOPE)
  set(${why} "${reason}" PARENT_SCOPE)
endfunction()

set(violations "")

# --- Includes ----------------------------------------------------------------
# Headers are named by path (sim/..., plugins/<name>/..., ../x.hpp), by their
# name under a sim/ library's include root (plr/sim/world.hpp is
# sim/world/include/plr/sim/world.hpp), as plr/shm/... or plr/dds/... (the
# kernel's), or, for the kernel's private headers, by their file name alone.
file(GLOB_RECURSE kernel_headers RELATIVE ${ROOT} ${ROOT}/kernel/*.hpp ${ROOT}/kernel/*.h)
set(kernel_names "")
foreach(h IN LISTS kernel_headers)
  get_filename_component(name ${h} NAME)
  list(APPEND kernel_names ${name})
endforeach()
file(GLOB_RECURSE sim_public_headers RELATIVE ${ROOT}/sim ${ROOT}/sim/*/include/*)
foreach(h IN LISTS sim_public_headers)
  if(h MATCHES "^([^/]+)/include/(.*)$")
    set(sim_owner_${CMAKE_MATCH_2} sim/${CMAKE_MATCH_1})
  endif()
endforeach()

file(GLOB_RECURSE files RELATIVE ${ROOT}
  ${ROOT}/kernel/*.cpp ${ROOT}/kernel/*.hpp ${ROOT}/kernel/*.h ${ROOT}/kernel/*.c
  ${ROOT}/sdk/*.cpp ${ROOT}/sdk/*.hpp ${ROOT}/sdk/*.h
  ${ROOT}/sim/*.cpp ${ROOT}/sim/*.hpp ${ROOT}/sim/*.h
  ${ROOT}/plugins/*.cpp ${ROOT}/plugins/*.hpp ${ROOT}/plugins/*.h ${ROOT}/plugins/*.c)
foreach(f IN LISTS files)
  area_of(${f} from)
  get_filename_component(folder ${f} DIRECTORY)
  file(STRINGS ${ROOT}/${f} lines REGEX "^[ \t]*#[ \t]*include[ \t]*[<\"]")
  foreach(line IN LISTS lines)
    string(REGEX REPLACE "^[ \t]*#[ \t]*include[ \t]*[<\"]([^>\"]*)[>\"].*" "\\1" inc "${line}")
    set(to "-")
    if(inc MATCHES "^(\\.\\./)*(kernel|sdk|sim|plugins/[^/]+)/")
      area_of(${CMAKE_MATCH_2} to)
    elseif(inc MATCHES "^\\.\\./" AND EXISTS ${ROOT}/${folder}/${inc})
      get_filename_component(target_file ${ROOT}/${folder}/${inc} ABSOLUTE)
      file(RELATIVE_PATH target_file ${ROOT} ${target_file})
      area_of(${target_file} to)
    elseif(DEFINED sim_owner_${inc})
      set(to ${sim_owner_${inc}})
    elseif(inc MATCHES "^plr/(shm|dds)/")
      set(to kernel)
    elseif(NOT inc MATCHES "/" AND inc IN_LIST kernel_names AND NOT from STREQUAL "kernel")
      # A kernel header's name: fine only when the including area has its own file of that name.
      string(REGEX MATCH "^(kernel|sdk|sim|plugins/[^/]+)" top ${folder})
      file(GLOB_RECURSE own ${ROOT}/${top}/${inc})
      if(NOT own)
        set(to kernel)
      endif()
    endif()
    if(NOT to STREQUAL "-")
      allowed("${from}" "${to}" ok why)
      if(NOT ok)
        list(APPEND violations "${f}: includes ${inc} (${why})")
      endif()
    endif()
  endforeach()
endforeach()

# --- Link graph ---------------------------------------------------------------
if(NOT EXISTS "${LINK_GRAPH}")
  message(FATAL_ERROR "no link graph at '${LINK_GRAPH}': reconfigure the build")
endif()
file(STRINGS ${LINK_GRAPH} graph)
foreach(entry IN LISTS graph)
  if(entry MATCHES "^target ([^ ]+) (.+)$")
    set(folder_of_${CMAKE_MATCH_1} ${CMAKE_MATCH_2})
  endif()
endforeach()
set(links 0)
foreach(entry IN LISTS graph)
  if(NOT entry MATCHES "^link ([^ ]+) ([^ ]+)$")
    continue()
  endif()
  set(t ${CMAKE_MATCH_1})
  set(dep ${CMAKE_MATCH_2})
  math(EXPR links "${links} + 1")
  area_of("${folder_of_${t}}" from)
  area_of("${folder_of_${dep}}" to)
  if(from STREQUAL "")
    continue()
  endif()
  allowed("${from}" "${to}" ok why)
  if(NOT ok)
    list(APPEND violations
      "target ${t} (${folder_of_${t}}) links ${dep} (${folder_of_${dep}}): ${why}")
  endif()
endforeach()
# --- Include paths -------------------------------------------------------------
# A plug-in's folders are on no include path but its own targets': neither
# named by another target nor exported by a plug-in target another one links.
function(check_include_folder t folder how)
  area_of("${folder}" owner)
  area_of("${folder_of_${t}}" user)
  if(owner MATCHES "^plugins/" AND NOT owner STREQUAL user)
    set(violations ${violations}
      "target ${t} (${folder_of_${t}}) ${how} ${folder} on its include path: only ${owner} may"
      PARENT_SCOPE)
  endif()
endfunction()
foreach(entry IN LISTS graph)
  if(entry MATCHES "^include ([^ ]+) (.+)$")
    check_include_folder(${CMAKE_MATCH_1} ${CMAKE_MATCH_2} has)
  elseif(entry MATCHES "^export ([^ ]+) (.+)$")
    list(APPEND exports_of_${CMAKE_MATCH_1} ${CMAKE_MATCH_2})
  endif()
endforeach()
foreach(entry IN LISTS graph)
  if(entry MATCHES "^link ([^ ]+) ([^ ]+)$")
    set(t ${CMAKE_MATCH_1})
    set(dep ${CMAKE_MATCH_2})
    foreach(folder IN LISTS exports_of_${dep})
      check_include_folder(${t} ${folder} "links ${dep}, which puts")
    endforeach()
  endif()
endforeach()

if(links EQUAL 0)
  message(FATAL_ERROR "the link graph ${LINK_GRAPH} lists no links: it cannot have been written right")
endif()

if(violations)
  list(JOIN violations "\n" text)
  message(FATAL_ERROR "dependency rule broken:\n${text}")
endif()
list(LENGTH files file_count)
message(STATUS "dependency rules hold (${file_count} files, ${links} links)")

cmake_minimum_required(VERSION 3.25)
# Who may depend on whom (docs/architecture.md), checked on the includes of
# every file and on the link graph of every target:
#   kernel/           -> sdk/
#   sdk/              -> nothing of ours
#   sim/              -> sdk/
#   plugins/<name>/   -> sdk/, sim/ (never another plug-in, never the kernel)
# Fails naming each offending file (and line) or target.
# cmake -DROOT=<source tree> -DLINK_GRAPH=<link_graph.txt> -P dependency_rules.cmake

# The area a path (relative to ROOT) belongs to: kernel, sdk, sim,
# plugins/<name>, or "" for what the rules do not cover (tests, the top).
function(area_of path out)
  if(path MATCHES "^(kernel|sdk|sim)(/|$)")
    set(${out} ${CMAKE_MATCH_1} PARENT_SCOPE)
  elseif(path MATCHES "^plugins/([^/]+)")
    set(${out} plugins/${CMAKE_MATCH_1} PARENT_SCOPE)
  else()
    set(${out} "" PARENT_SCOPE)
  endif()
endfunction()

# Whether `from` may depend on `to` (areas as above; "" is the top folder,
# whose helpers such as plr_warnings every area may use).
function(allowed from to out)
  set(ok FALSE)
  if(to STREQUAL "" OR to STREQUAL from OR (NOT from STREQUAL "sdk" AND to STREQUAL "sdk"))
    set(ok TRUE)
  elseif(from MATCHES "^plugins/" AND to STREQUAL "sim")
    set(ok TRUE)
  endif()
  set(${out} ${ok} PARENT_SCOPE)
endfunction()

set(violations "")

# --- Includes ----------------------------------------------------------------
# Headers are named by path (sim/..., plugins/<name>/..., plr/sim/...,
# plr/shm/...) or, for the kernel's private headers, by their file name alone.
file(GLOB_RECURSE kernel_headers RELATIVE ${ROOT} ${ROOT}/kernel/*.hpp ${ROOT}/kernel/*.h)
set(kernel_names "")
foreach(h IN LISTS kernel_headers)
  get_filename_component(name ${h} NAME)
  list(APPEND kernel_names ${name})
endforeach()

file(GLOB_RECURSE files RELATIVE ${ROOT}
  ${ROOT}/kernel/*.cpp ${ROOT}/kernel/*.hpp ${ROOT}/kernel/*.h ${ROOT}/kernel/*.c
  ${ROOT}/sdk/*.cpp ${ROOT}/sdk/*.hpp ${ROOT}/sdk/*.h
  ${ROOT}/sim/*.cpp ${ROOT}/sim/*.hpp ${ROOT}/sim/*.h
  ${ROOT}/plugins/*.cpp ${ROOT}/plugins/*.hpp ${ROOT}/plugins/*.h ${ROOT}/plugins/*.c)
foreach(f IN LISTS files)
  area_of(${f} from)
  file(STRINGS ${ROOT}/${f} lines REGEX "^[ \t]*#[ \t]*include[ \t]*[<\"]")
  set(n 0)
  foreach(line IN LISTS lines)
    string(REGEX REPLACE "^[ \t]*#[ \t]*include[ \t]*[<\"]([^>\"]*)[>\"].*" "\\1" inc "${line}")
    set(to "-")
    if(inc MATCHES "^(\\.\\./)*(kernel|sdk|sim|plugins/[^/]+)/")
      area_of(${CMAKE_MATCH_2} to)
    elseif(inc MATCHES "^plr/sim/")
      set(to sim)
    elseif(inc MATCHES "^plr/(shm|dds)/")
      set(to kernel)
    elseif(NOT inc MATCHES "/" AND inc IN_LIST kernel_names AND NOT from STREQUAL "kernel")
      # A kernel header's name: fine only when the including area has its own file of that name.
      get_filename_component(folder ${f} DIRECTORY)
      string(REGEX MATCH "^(kernel|sdk|sim|plugins/[^/]+)" top ${folder})
      file(GLOB_RECURSE own ${ROOT}/${top}/${inc})
      if(NOT own)
        set(to kernel)
      endif()
    endif()
    if(NOT to STREQUAL "-")
      allowed("${from}" "${to}" ok)
      if(NOT ok)
        list(APPEND violations "${f}: includes ${inc} (${from} may not depend on ${to})")
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
  allowed("${from}" "${to}" ok)
  if(NOT ok)
    list(APPEND violations
      "target ${t} (${folder_of_${t}}) links ${dep} (${folder_of_${dep}}): ${from} may not depend on ${to}")
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

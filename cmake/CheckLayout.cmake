# Fails the build when a file of one stage includes a header of a stage it
# does not depend on (directly or through others), or when a stage other than
# `device` includes the OpenCL headers. Run as a build step by
# host/CMakeLists.txt:
#   cmake -DSOURCE_DIR=<repo> -DSTAGES="util:;io:util;block:util,io;..." -P CheckLayout.cmake
# STAGES is host/CMakeLists.txt's table of each stage's direct dependencies.

cmake_minimum_required(VERSION 3.18)

set(stage_names "")
foreach(entry IN LISTS STAGES)
  if(entry STREQUAL "")
    continue()
  endif()
  string(REPLACE ":" ";" parts "${entry}")
  list(GET parts 0 name)
  list(LENGTH parts count)
  set(direct_${name} "")
  if(count GREATER 1)
    list(GET parts 1 deps)
    string(REPLACE "," ";" direct_${name} "${deps}")
  endif()
  list(APPEND stage_names ${name})
endforeach()

# Transitive closure: stages are declared in dependency order, so each
# dependency's closure is complete when a stage is reached.
foreach(name IN LISTS stage_names)
  set(reach_${name} ${name})
  foreach(dep IN LISTS direct_${name})
    if(NOT DEFINED reach_${dep})
      message(FATAL_ERROR "host/CMakeLists.txt: stage ${name} depends on ${dep}, "
                          "which is not declared before it")
    endif()
    list(APPEND reach_${name} ${reach_${dep}})
  endforeach()
  list(REMOVE_DUPLICATES reach_${name})
endforeach()

# Device headers that expose OpenCL types: those that include <CL/...>, or
# another such header. Only the device stage may include them.
file(GLOB device_headers ${SOURCE_DIR}/host/device/*.h)
set(opencl_headers "")
set(changed TRUE)
while(changed)
  set(changed FALSE)
  foreach(header IN LISTS device_headers)
    get_filename_component(header_name ${header} NAME)
    if("device/${header_name}" IN_LIST opencl_headers)
      continue()
    endif()
    file(STRINGS ${header} lines REGEX "^[ \t]*#[ \t]*include")
    foreach(line IN LISTS lines)
      if(line MATCHES "<CL/" OR (line MATCHES "\"(device/[a-z_]+\\.h)\"" AND
                                 CMAKE_MATCH_1 IN_LIST opencl_headers))
        list(APPEND opencl_headers "device/${header_name}")
        set(changed TRUE)
        break()
      endif()
    endforeach()
  endforeach()
endwhile()

set(errors "")
foreach(name IN LISTS stage_names)
  file(GLOB files ${SOURCE_DIR}/host/${name}/*.h ${SOURCE_DIR}/host/${name}/*.cc
       ${SOURCE_DIR}/include/sapmvs/${name}/*.h)
  foreach(file IN LISTS files)
    file(RELATIVE_PATH rel ${SOURCE_DIR} ${file})
    file(STRINGS ${file} lines REGEX "^[ \t]*#[ \t]*include[ \t]*[<\"]")
    foreach(line IN LISTS lines)
      if(line MATCHES "#[ \t]*include[ \t]*<CL/" AND NOT name STREQUAL "device")
        list(APPEND errors "${rel}: includes an OpenCL header: only host/device/ may")
      elseif(NOT name STREQUAL "device" AND line MATCHES "\"(device/[a-z_]+\\.h)\"" AND
             CMAKE_MATCH_1 IN_LIST opencl_headers)
        list(APPEND errors "${rel}: includes ${CMAKE_MATCH_1}, which exposes OpenCL types: "
                           "only host/device/ may")
      elseif(line MATCHES "#[ \t]*include[ \t]*\"(sapmvs/)?([a-z_]+)/")
        set(target ${CMAKE_MATCH_2})
        if(target IN_LIST stage_names AND NOT target IN_LIST reach_${name})
          list(APPEND errors "${rel}: includes a header of stage ${target}, which stage ${name} "
                             "does not depend on (host/CMakeLists.txt)")
        endif()
      endif()
    endforeach()
  endforeach()
endforeach()

if(errors)
  list(JOIN errors "\n" text)
  message(FATAL_ERROR "${text}")
endif()

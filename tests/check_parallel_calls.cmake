# Fails when a file of sim/ or engine/ other than sim/parallel.h calls TBB's loops or task groups directly:
# the ThreadSanitizer annotations of sim/parallel.h see only its wrappers (docs/robustness.md, "Races").
#   cmake -DFP_SOURCE_DIR=<repo> -P this file
cmake_minimum_required(VERSION 3.22)
file(GLOB_RECURSE sources ${FP_SOURCE_DIR}/sim/*.cpp ${FP_SOURCE_DIR}/sim/*.h ${FP_SOURCE_DIR}/engine/*.cpp
     ${FP_SOURCE_DIR}/engine/*.h)
set(found "")
foreach(file IN LISTS sources)
  if(file STREQUAL "${FP_SOURCE_DIR}/sim/parallel.h")
    continue()
  endif()
  file(STRINGS ${file} lines REGEX "tbb::(parallel_[a-z_]+|task_group|parallel_invoke|task_arena)[ (<]")
  foreach(line IN LISTS lines)
    file(RELATIVE_PATH rel ${FP_SOURCE_DIR} ${file})
    string(REPLACE ";" "," line "${line}")
    list(APPEND found "${rel}: ${line}")
  endforeach()
endforeach()
if(found)
  list(JOIN found "\n" text)
  message(FATAL_ERROR "direct TBB parallel calls (use sim/parallel.h):\n${text}")
endif()
message(STATUS "every parallel call goes through sim/parallel.h")

# Checks the rules of the house (STYLE.md, docs/architecture.md) and fails with one line per broken rule.
#   cmake -DFP_SOURCE_DIR=<repo> -DFP_LINK_GRAPH=<build>/tests/architecture/link_graph.cmake -P this file
# Includes: sim/ includes no graphics, window, GUI or XR header and nothing of input/, render/ or engine/;
#   input/ and render/ include nothing of engine/; render/ nothing of input/; input/ nothing of render/.
# Links (the transitive closure of the CMake link graph, since readelf's NEEDED entries hide what the linker
#   dropped): fluid_sim reaches Eigen, TBB and threads only; fluid_input and fluid_render never reach the
#   engine, nor each other; the scene loader no renderer; the simulation's test suites link the simulation
#   (and, for the physics suite, the scene loader) alone.
# Built executables: the simulation's test suites need no GL, OSMesa, GLEW, GLFW or PNG library (readelf -d).
cmake_minimum_required(VERSION 3.22)

set(violations "")
macro(violation text)
  list(APPEND violations "${text}")
endmacro()

# ---- includes --------------------------------------------------------------------------------------------------
# graphics, window, GUI and XR headers, matched on the lower-cased include path
set(graphics_headers "^(gl|gles[0-9]*|egl|glfw|glad|khr|openxr|epoxy|opengl|vulkan)/|^imgui|^glew|osmesa")

function(check_includes folder forbidden_folders forbid_graphics)
  file(GLOB_RECURSE files RELATIVE ${FP_SOURCE_DIR} ${FP_SOURCE_DIR}/${folder}/*.h ${FP_SOURCE_DIR}/${folder}/*.hpp
       ${FP_SOURCE_DIR}/${folder}/*.cpp ${FP_SOURCE_DIR}/${folder}/*.cc)
  if(NOT files)
    set(violations "${violations};${folder}/: no sources found under ${FP_SOURCE_DIR}" PARENT_SCOPE)
    return()
  endif()
  set(found "")
  foreach(file IN LISTS files)
    file(STRINGS ${FP_SOURCE_DIR}/${file} lines REGEX "^[ \t]*#[ \t]*include[ \t]*[<\"]")
    foreach(line IN LISTS lines)
      if(NOT line MATCHES "#[ \t]*include[ \t]*[<\"]([^>\"]+)[>\"]")
        continue()
      endif()
      set(header "${CMAKE_MATCH_1}")
      string(TOLOWER "${header}" lower)
      foreach(other IN LISTS forbidden_folders)
        if(header MATCHES "^${other}/")
          list(APPEND found "${file} includes ${header}: ${folder}/ must not depend on ${other}/")
        endif()
      endforeach()
      if(forbid_graphics AND lower MATCHES "${graphics_headers}")
        list(APPEND found "${file} includes ${header}: ${folder}/ must stay free of GL, GLFW, ImGui and OpenXR")
      endif()
    endforeach()
  endforeach()
  set(violations "${violations};${found}" PARENT_SCOPE)
endfunction()

check_includes(sim "input;render;engine" TRUE)
check_includes(input "engine;render" FALSE)
check_includes(render "engine;input" FALSE)

# ---- links -----------------------------------------------------------------------------------------------------
if(NOT EXISTS "${FP_LINK_GRAPH}")
  message(FATAL_ERROR "architecture: ${FP_LINK_GRAPH} is missing (configure the build first)")
endif()
include(${FP_LINK_GRAPH})

# everything `target` links, directly or through the project's own libraries (imported targets and plain
# libraries are leaves)
function(link_closure target out)
  set(seen "")
  set(queue ${target})
  while(queue)
    list(POP_FRONT queue t)
    set(deps ${FP_ILINK_${t}})
    if(t STREQUAL target AND DEFINED FP_LINK_${t})
      set(deps ${FP_LINK_${t}})
    endif()
    foreach(d IN LISTS deps)
      # private dependencies of static libraries come as $<LINK_ONLY:...>; they are linked all the same
      string(REGEX REPLACE "^\\$<LINK_ONLY:(.*)>$" "\\1" d "${d}")
      if(d STREQUAL "" OR d IN_LIST seen)
        continue()
      endif()
      list(APPEND seen ${d})
      if(d IN_LIST FP_TARGETS)
        list(APPEND queue ${d})
      endif()
    endforeach()
  endwhile()
  set(${out} ${seen} PARENT_SCOPE)
endfunction()

# `target` may reach only what matches `allowed` (a regex on each item of its closure)
function(check_links_only target allowed why)
  if(NOT target IN_LIST FP_TARGETS)
    set(violations "${violations};${target}: no such target (the rule names a target that is gone)" PARENT_SCOPE)
    return()
  endif()
  link_closure(${target} closure)
  set(found "")
  foreach(item IN LISTS closure)
    if(NOT item MATCHES "${allowed}")
      list(APPEND found "${target} links ${item}: ${why}")
    endif()
  endforeach()
  set(violations "${violations};${found}" PARENT_SCOPE)
endfunction()

# `target` must not reach anything that matches `forbidden`
function(check_links_not target forbidden why)
  if(NOT target IN_LIST FP_TARGETS)
    set(violations "${violations};${target}: no such target (the rule names a target that is gone)" PARENT_SCOPE)
    return()
  endif()
  link_closure(${target} closure)
  set(found "")
  foreach(item IN LISTS closure)
    if(item MATCHES "${forbidden}")
      list(APPEND found "${target} links ${item}: ${why}")
    endif()
  endforeach()
  set(violations "${violations};${found}" PARENT_SCOPE)
endfunction()

# what the simulation core may link: the project's compile options, Eigen, TBB, threads and the C++ runtime
set(sim_deps "^(fp_options|fluid_sim|Eigen3::Eigen|TBB::tbb|TBB::tbbmalloc|Threads::Threads|m|dl|pthread|-pthread)$")
set(gtest "^GTest::(gtest|gtest_main|GTest|Main)$")
set(graphics_libs "(OSMESA|osmesa|GLEW|glfw|IMGUI|imgui|OpenGL|GL$|PNG|png|openxr|OpenXR)")

check_links_only(fluid_sim "${sim_deps}" "the simulation core links Eigen and TBB only")
check_links_not(fluid_input "^(fluid_engine|fluid_desktop|fluid_render)$|${graphics_libs}"
                "input/ produces collider poses from sim types, never the engine or the renderer")
check_links_not(fluid_render "^(fluid_engine|fluid_desktop|fluid_input)$"
                "render/ reads the simulation only, never the engine or input/")
check_links_only(fluid_scene "${sim_deps}|^(fluid_scene|nlohmann_json::nlohmann_json)$"
                 "the scene loader turns JSON into a sim::SceneDesc and needs nothing else")
check_links_only(test_sim_unit "${sim_deps}|${gtest}" "the simulation's unit tests link fluid_sim alone")
check_links_only(test_physics "${sim_deps}|${gtest}|^(fluid_scene|nlohmann_json::nlohmann_json)$"
                 "the physics tests link fluid_sim and the scene loader alone")

# ---- built executables -----------------------------------------------------------------------------------------
find_program(READELF readelf)
if(READELF)
  foreach(exe test_sim_unit test_physics)
    if(NOT DEFINED FP_FILE_${exe} OR NOT EXISTS "${FP_FILE_${exe}}")
      continue()  # not built (ctest runs after the build; a partial build checks what is there)
    endif()
    execute_process(COMMAND ${READELF} -d ${FP_FILE_${exe}} OUTPUT_VARIABLE dynamic RESULT_VARIABLE rc)
    if(NOT rc EQUAL 0)
      violation("${exe}: readelf -d failed")
      continue()
    endif()
    string(REGEX MATCHALL "\\(NEEDED\\)[^\n]*\\[[^]\n]+\\]" needed "${dynamic}")
    foreach(entry IN LISTS needed)
      if(entry MATCHES "\\[(lib(GL|GLX|EGL|OSMesa|GLEW|glfw|png|openxr_loader|imgui)[^]]*)\\]")
        violation("${exe} needs ${CMAKE_MATCH_1}: the simulation's tests need no graphics library")
      endif()
    endforeach()
  endforeach()
endif()

list(REMOVE_ITEM violations "")
list(LENGTH violations count)
if(count GREATER 0)
  list(JOIN violations "\n  " text)
  message(FATAL_ERROR "architecture: ${count} rule(s) broken:\n  ${text}")
endif()
message(STATUS "architecture: include and link rules hold")

# rotorguard_module(NAME SOURCES ... DEPENDS ... [PRIVATE_DEPENDS ...] [NO_PRECOMPILED_HEADERS])
# One static library per module, target rotorguard_<name> with alias rotorguard::<name>.
# Public headers live in src/<name>/include/rotorguard/<name>/; a module sees another module's
# headers only if it links that module, so the layering of docs/architecture.md is enforced by the build.
set(ROTORGUARD_MODULES "" CACHE INTERNAL "")
function(rotorguard_module name)
  cmake_parse_arguments(ARG "NO_PRECOMPILED_HEADERS" "" "SOURCES;DEPENDS;PRIVATE_DEPENDS" ${ARGN})
  set(target rotorguard_${name})
  add_library(${target} STATIC ${ARG_SOURCES})
  add_library(rotorguard::${name} ALIAS ${target})
  target_include_directories(${target} PUBLIC
    $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  target_link_libraries(${target} PUBLIC ${ARG_DEPENDS} PRIVATE ${ARG_PRIVATE_DEPENDS}
    $<BUILD_INTERFACE:rotorguard_warnings>)
  set_target_properties(${target} PROPERTIES POSITION_INDEPENDENT_CODE ON)
  if(NOT ARG_NO_PRECOMPILED_HEADERS)
    rotorguard_precompiled_headers(${target} LIBRARY)
  endif()
  install(DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR}/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
  set(ROTORGUARD_MODULES ${ROTORGUARD_MODULES} ${target} CACHE INTERNAL "")
endfunction()

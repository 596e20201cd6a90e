# Layers enforced by the build. Each layer is a target whose include path is a folder of symbolic links
# to its own headers and to those of the layers it may use (build/layers/<layer>/sinew/<name> ->
# include/sinew/<name>), so a layer that includes a header of a layer above it does not compile:
#
#   driver -> scenes, io -> solver -> algebra -> discretization -> materials -> core
#
# sinew_layer(<layer> <STATIC|INTERFACE> [SOURCES ...] [USES <layers below>...] [LINK <libraries>...])
function(sinew_layer layer kind)
  cmake_parse_arguments(L "" "" "SOURCES;USES;LINK" ${ARGN})
  set(view ${PROJECT_BINARY_DIR}/layers/${layer})
  file(REMOVE_RECURSE ${view})  # a layer that stopped using another must stop seeing it
  file(MAKE_DIRECTORY ${view}/sinew)
  foreach(visible ${layer} ${L_USES})
    file(CREATE_LINK ${PROJECT_SOURCE_DIR}/include/sinew/${visible} ${view}/sinew/${visible} SYMBOLIC)
  endforeach()
  set(target sinew_${layer})
  if(kind STREQUAL "INTERFACE")
    add_library(${target} INTERFACE)
    target_include_directories(${target} INTERFACE ${view})
    target_link_libraries(${target} INTERFACE ${L_LINK})
  else()
    add_library(${target} ${kind} ${L_SOURCES})
    target_include_directories(${target} PUBLIC ${view})
    target_link_libraries(${target} PUBLIC ${L_LINK})
    target_compile_options(${target} PRIVATE -Wall -Wextra)
  endif()
  set_property(GLOBAL APPEND PROPERTY SINEW_LAYERS ${layer})
endfunction()

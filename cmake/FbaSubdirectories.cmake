# fba_add_subdirectories([EXCLUDE <names>...]): adds every folder beside the calling
# CMakeLists.txt that has a CMakeLists.txt of its own, so a new test group or tool is one folder.
function(fba_add_subdirectories)
  cmake_parse_arguments(ARG "" "" "EXCLUDE" ${ARGN})
  file(GLOB dirs LIST_DIRECTORIES true ${CMAKE_CURRENT_SOURCE_DIR}/*)
  foreach(dir ${dirs})
    get_filename_component(name ${dir} NAME)
    if(EXISTS ${dir}/CMakeLists.txt AND NOT name IN_LIST ARG_EXCLUDE)
      add_subdirectory(${dir})
    endif()
  endforeach()
endfunction()

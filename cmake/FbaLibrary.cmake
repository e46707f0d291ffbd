# fba_add_library(<name> <sources...>)
#
# Builds the installed shared library fba_<name> from the sources, as fba::<name> both here and
# for a project that finds the installed fba: its headers are its folder's include/ (installed
# with it) and it joins the fbaTargets export. What it links the caller says.
function(fba_add_library name)
  set(target fba_${name})
  add_library(${target} SHARED ${ARGN})
  add_library(fba::${name} ALIAS ${target})
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${name})
  target_include_directories(${target} PUBLIC
    $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include> $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  install(TARGETS ${target} EXPORT fbaTargets LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
  install(DIRECTORY include/fba DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
endfunction()

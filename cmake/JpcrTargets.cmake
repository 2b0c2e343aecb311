# Helpers that give every jpcr library the same shape: target jpcr_<name>, alias jpcr::<name>,
# headers reachable as "jpcr/<folder>/<file>.hpp", warnings on, installed and exported.

function(jpcr_target_defaults target)
  target_compile_options(${target} PRIVATE
    $<$<COMPILE_LANGUAGE:CXX>:-Wall -Wextra>
    $<$<COMPILE_LANGUAGE:CUDA>:--expt-relaxed-constexpr -diag-suppress=20012,20013,20014,20015
      -Xcompiler=-Wall,-Wextra>)
  if(OpenMP_CXX_FOUND)
    target_link_libraries(${target} PRIVATE OpenMP::OpenMP_CXX)
  endif()
endfunction()

# jpcr_add_library(<name> FOLDER <dir> SOURCES ... [PUBLIC ...] [PRIVATE ...] [INTERNAL ...])
# INTERNAL names the folder's headers that only its own sources (and the tests) include: they
# are not installed, so a consumer never sees the CUDA runtime, Ceres, MRPT or yaml-cpp headers
# they pull in.
function(jpcr_add_library name)
  cmake_parse_arguments(ARG "" "FOLDER" "SOURCES;PUBLIC;PRIVATE;INTERNAL" ${ARGN})
  set(target jpcr_${name})
  add_library(${target} ${ARG_SOURCES})
  add_library(jpcr::${name} ALIAS ${target})
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${name} OUTPUT_NAME jpcr_${name})
  target_include_directories(${target} PUBLIC
    $<BUILD_INTERFACE:${JPCR_BUILD_INCLUDE_DIR}>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  target_compile_features(${target} PUBLIC cxx_std_17)
  target_link_libraries(${target} PUBLIC ${ARG_PUBLIC} PRIVATE ${ARG_PRIVATE})
  jpcr_target_defaults(${target})
  install(TARGETS ${target} EXPORT jpcrTargets
          ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
          LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
          RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
  set(exclude)
  foreach(header IN LISTS ARG_INTERNAL)
    list(APPEND exclude PATTERN ${header} EXCLUDE)
  endforeach()
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${ARG_FOLDER}/
          DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/jpcr/${ARG_FOLDER}
          FILES_MATCHING PATTERN "*.hpp" PATTERN "*.cuh" PATTERN "*.h" ${exclude})
endfunction()

# jpcr_add_tool(<name> SOURCES ... LIBS ...): a command-line program, installed.
function(jpcr_add_tool name)
  cmake_parse_arguments(ARG "" "" "SOURCES;LIBS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_LIBS})
  jpcr_target_defaults(${name})
  install(TARGETS ${name} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
endfunction()

# Helpers that keep every module's CMakeLists.txt short and uniform.
set(IMUMATCH_MODULES "" CACHE INTERNAL "")

function(imumatch_warnings TARGET)
  target_compile_options(${TARGET} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor
                                           $<$<BOOL:${IMUMATCH_WERROR}>:-Werror>)
endfunction()

# imumatch_add_library(NAME SRCS ... HDRS ... PUBLIC_LINK ... PRIVATE_LINK ...)
# Creates target imumatch_NAME, alias imumatch::NAME, installs headers to include/imumatch/NAME.
function(imumatch_add_library NAME)
  cmake_parse_arguments(ARG "" "" "SRCS;HDRS;PUBLIC_LINK;PRIVATE_LINK" ${ARGN})
  set(T imumatch_${NAME})
  add_library(${T} ${ARG_SRCS} ${ARG_HDRS})
  add_library(imumatch::${NAME} ALIAS ${T})
  set_target_properties(${T} PROPERTIES EXPORT_NAME ${NAME})
  target_include_directories(${T} PUBLIC $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/src>
                                         $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  target_link_libraries(${T} PUBLIC ${ARG_PUBLIC_LINK} PRIVATE ${ARG_PRIVATE_LINK})
  target_compile_features(${T} PUBLIC cxx_std_17)
  imumatch_warnings(${T})
  install(TARGETS ${T} EXPORT imumatchTargets
          ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
          LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
          RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
  install(FILES ${ARG_HDRS} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/imumatch/${NAME})
  set(IMUMATCH_MODULES ${IMUMATCH_MODULES} ${T} CACHE INTERNAL "")
endfunction()

# imumatch_add_test(NAME SRCS ... LINK ... [LABELS ...] [SUITES_IN_ONE_PROCESS ...])
# A GoogleTest executable; each TEST is registered with ctest at test time. Each suite listed in
# SUITES_IN_ONE_PROCESS is one ctest test instead (named after the suite, all its TESTs in one
# process): for suites whose tests share an expensive run through a function-local static (an
# eval on real data), which one process per TEST would repeat for every TEST.
function(imumatch_add_test NAME)
  if(NOT IMUMATCH_BUILD_TESTS)
    return()
  endif()
  cmake_parse_arguments(ARG "" "TIMEOUT" "SRCS;LINK;LABELS;SUITES_IN_ONE_PROCESS" ${ARGN})
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 300)
  endif()
  add_executable(${NAME} ${ARG_SRCS})
  target_link_libraries(${NAME} PRIVATE ${ARG_LINK} imumatch_testing GTest::gtest GTest::gtest_main GTest::gmock)
  imumatch_warnings(${NAME})
  set(filter "")
  foreach(suite IN LISTS ARG_SUITES_IN_ONE_PROCESS)
    list(APPEND filter "${suite}.*")
    add_test(NAME ${suite} COMMAND ${NAME} --gtest_filter=${suite}.*)
    # A suite's TESTs one after the other: the time of each TEST, summed.
    math(EXPR suite_timeout "${ARG_TIMEOUT} * 3")
    set_tests_properties(${suite} PROPERTIES TIMEOUT ${suite_timeout} LABELS "${ARG_LABELS}")
  endforeach()
  set(discover_filter "")
  if(filter)
    list(JOIN filter ":" filter)
    set(discover_filter TEST_FILTER "-${filter}")
  endif()
  gtest_discover_tests(${NAME} DISCOVERY_MODE PRE_TEST DISCOVERY_TIMEOUT 60 ${discover_filter}
                       PROPERTIES TIMEOUT ${ARG_TIMEOUT} LABELS "${ARG_LABELS}")
endfunction()

# imumatch_add_benchmark(NAME SRCS ... LINK ...): a Google Benchmark executable (not run by ctest).
function(imumatch_add_benchmark NAME)
  if(NOT IMUMATCH_BUILD_BENCHMARKS)
    return()
  endif()
  cmake_parse_arguments(ARG "" "" "SRCS;LINK" ${ARGN})
  add_executable(${NAME} ${ARG_SRCS})
  target_link_libraries(${NAME} PRIVATE ${ARG_LINK} benchmark::benchmark)
  imumatch_warnings(${NAME})
endfunction()

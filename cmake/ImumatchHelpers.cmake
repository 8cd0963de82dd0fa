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

# imumatch_add_test(NAME SRCS ... LINK ... [LABELS ...] [TIMEOUT seconds])
# A GoogleTest executable, registered with ctest as one entry per test suite (`Suite` runs
# `--gtest_filter=Suite.*:*/Suite.*`, TEST_P instances included), named after the suite, plus
# `NAME.others` for whatever the suites read from the sources do not cover (0 tests normally; a
# suite added since the last configure). Not one entry per TEST: starting a test process that links
# OpenCV costs 0.2 s, 0.45 s under ASan, which for ~380 TESTs was a third of the test time. TIMEOUT
# is per suite (default 900 s). On a first run the suites with the most TESTs start first, those of
# `integration`-labelled executables before the rest (COST); later ctest orders by recorded times.
function(imumatch_add_test NAME)
  if(NOT IMUMATCH_BUILD_TESTS)
    return()
  endif()
  cmake_parse_arguments(ARG "" "TIMEOUT" "SRCS;LINK;LABELS" ${ARGN})
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 900)
  endif()
  add_executable(${NAME} ${ARG_SRCS})
  target_link_libraries(${NAME} PRIVATE ${ARG_LINK} imumatch_testing GTest::gtest GTest::gtest_main GTest::gmock)
  imumatch_warnings(${NAME})
  set(test_suites "")  # the suite of every TEST read from the sources
  foreach(src IN LISTS ARG_SRCS)
    get_filename_component(path ${src} ABSOLUTE)
    set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${path})
    file(STRINGS ${path} lines REGEX "^(TEST|TEST_F|TEST_P)\\([A-Za-z0-9_]+,")
    list(TRANSFORM lines REPLACE "^TEST[_FP]*\\(([A-Za-z0-9_]+),.*" "\\1")
    list(APPEND test_suites ${lines})
  endforeach()
  set(suites ${test_suites})
  list(REMOVE_DUPLICATES suites)
  set(cost_factor 1)
  if("integration" IN_LIST ARG_LABELS)
    set(cost_factor 10)
  endif()
  set(all_filters "")
  foreach(suite IN LISTS suites)
    set(tests ${test_suites})
    list(FILTER tests INCLUDE REGEX "^${suite}$")
    list(LENGTH tests count)
    math(EXPR cost "${count} * ${cost_factor}")
    add_test(NAME ${suite} COMMAND ${NAME} --gtest_filter=${suite}.*:*/${suite}.*)
    set_tests_properties(${suite} PROPERTIES TIMEOUT ${ARG_TIMEOUT} LABELS "${ARG_LABELS}" COST ${cost})
    list(APPEND all_filters "${suite}.*" "*/${suite}.*")
  endforeach()
  list(JOIN all_filters ":" all_filters)
  add_test(NAME ${NAME}.others COMMAND ${NAME} --gtest_filter=-${all_filters})
  set_tests_properties(${NAME}.others PROPERTIES TIMEOUT ${ARG_TIMEOUT} LABELS "${ARG_LABELS}")
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

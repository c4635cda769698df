# gcpstereo_add_module(NAME SOURCES ... [PUBLIC_DEPS ...] [PRIVATE_DEPS ...])
# Creates the static library gcpstereo_<NAME> from modules/<NAME>/; public headers live in
# modules/<NAME>/include/gcpstereo/<NAME>/ and are included as <gcpstereo/<NAME>/x.h>.
function(gcpstereo_add_module name)
  cmake_parse_arguments(ARG "" "" "SOURCES;PUBLIC_DEPS;PRIVATE_DEPS" ${ARGN})
  add_library(gcpstereo_${name} STATIC ${ARG_SOURCES})
  target_include_directories(gcpstereo_${name} PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include
                                                PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/src)
  target_link_libraries(gcpstereo_${name} PUBLIC ${ARG_PUBLIC_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  add_library(gcpstereo::${name} ALIAS gcpstereo_${name})
endfunction()

# gcpstereo_add_test(MODULE SOURCES ... [DEPS ...])
# One GoogleTest executable per module: tests/<MODULE>/ -> gcpstereo_<MODULE>_test. Each test case
# becomes a CTest test; tests that read ../shared/data skip with a message when it is absent.
function(gcpstereo_add_test module)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  set(target gcpstereo_${module}_test)
  add_executable(${target} ${ARG_SOURCES})
  target_link_libraries(${target} PRIVATE ${ARG_DEPS} gcpstereo_test_support GTest::gtest)
  gtest_discover_tests(${target} DISCOVERY_MODE PRE_TEST DISCOVERY_TIMEOUT 60
                       PROPERTIES LABELS ${module} TIMEOUT ${GCPSTEREO_TEST_TIMEOUT})
endfunction()

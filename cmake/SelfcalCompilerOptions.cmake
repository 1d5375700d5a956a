# Warnings as errors and the optional sanitizers, for our own targets only.
# Never touches global flags, so third-party code and generated code build as they are.
function(selfcal_target_options target)
  target_compile_options(${target} PRIVATE
    $<$<COMPILE_LANGUAGE:CXX>:-Wall -Wextra -Wconversion -Werror>)
  if(SELFCAL_SANITIZE)
    target_compile_options(${target} PRIVATE -fsanitize=address,undefined -fno-omit-frame-pointer
                                              -fno-sanitize-recover=undefined)
    target_link_options(${target} PRIVATE -fsanitize=address,undefined)
  endif()
endfunction()

# A library of ours: target selfcal_<name>, alias selfcal::<name>, our compile options.
#   selfcal_add_library(<name> <source>... [PUBLIC <dependency>...] [PRIVATE <dependency>...])
function(selfcal_add_library name)
  cmake_parse_arguments(ARG "" "" "PUBLIC;PRIVATE" ${ARGN})
  add_library(selfcal_${name} ${ARG_UNPARSED_ARGUMENTS})
  add_library(selfcal::${name} ALIAS selfcal_${name})
  if(ARG_PUBLIC)
    target_link_libraries(selfcal_${name} PUBLIC ${ARG_PUBLIC})
  endif()
  if(ARG_PRIVATE)
    target_link_libraries(selfcal_${name} PRIVATE ${ARG_PRIVATE})
  endif()
  selfcal_target_options(selfcal_${name})
endfunction()

# Sets test `name`'s time limit: `seconds` times SELFCAL_TEST_TIMEOUT_SCALE.
function(selfcal_test_timeout name seconds)
  math(EXPR timeout "${seconds} * ${SELFCAL_TEST_TIMEOUT_SCALE}")
  set_tests_properties(${name} PROPERTIES TIMEOUT ${timeout})
endfunction()

# Adds a GoogleTest executable built from SOURCES, linked to LIBS, registered with CTest.
function(selfcal_add_test name)
  cmake_parse_arguments(ARG "" "TIMEOUT" "SOURCES;LIBS;LABELS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  selfcal_target_options(${name})
  target_link_libraries(${name} PRIVATE ${ARG_LIBS} GTest::gtest GTest::gtest_main)
  add_test(NAME ${name} COMMAND ${name})
  set(timeout 120)
  if(ARG_TIMEOUT)
    set(timeout ${ARG_TIMEOUT})
  endif()
  selfcal_test_timeout(${name} ${timeout})
  set_tests_properties(${name} PROPERTIES ENVIRONMENT "SELFCAL_SOURCE_DIR=${PROJECT_SOURCE_DIR}")
  if(ARG_LABELS)
    set_tests_properties(${name} PROPERTIES LABELS "${ARG_LABELS}")
  endif()
endfunction()

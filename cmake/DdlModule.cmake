# ddl_add_module(<name> SOURCES ... [DEPS ...])
#   One static library per module: target ddl_<name>, alias ddl::<name>, includes rooted at src/.
#   DEPS are public link dependencies (other ddl::modules or imported targets); a new arrow between
#   modules is a design decision (ARCHITECTURE.md, section 2).
function(ddl_add_module name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_library(ddl_${name} STATIC ${ARG_SOURCES})
  add_library(ddl::${name} ALIAS ddl_${name})
  target_include_directories(ddl_${name} PUBLIC ${PROJECT_SOURCE_DIR}/src)
  target_link_libraries(ddl_${name} PUBLIC ${ARG_DEPS})
endfunction()

# ddl_add_test(<name> SOURCES ... [DEPS ...] [LABELS ...])
#   One GoogleTest executable per module (tests/<module>/), registered with CTest per test case.
#   Tests find ../shared through the DDL_SHARED_DIR environment variable set here.
function(ddl_add_test name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS;LABELS" ${ARGN})
  # serial_opencv_under_tsan.cc: OpenCV on one thread under ThreadSanitizer (see the file).
  add_executable(test_${name} ${ARG_SOURCES}
                 ${PROJECT_SOURCE_DIR}/tests/common/serial_opencv_under_tsan.cc)
  target_link_libraries(test_${name} PRIVATE ${ARG_DEPS} opencv_core GTest::gtest GTest::gtest_main)
  target_include_directories(test_${name} PRIVATE ${PROJECT_SOURCE_DIR}/tests/common)
  target_compile_definitions(test_${name} PRIVATE
    DDL_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    DDL_DEFAULT_SHARED_DIR="${PROJECT_SOURCE_DIR}/../shared")
  set(labels ${ARG_LABELS})
  if(NOT labels)
    set(labels unit)
  endif()
  gtest_discover_tests(test_${name}
    WORKING_DIRECTORY ${CMAKE_CURRENT_BINARY_DIR}
    PROPERTIES LABELS "${labels}"
    DISCOVERY_TIMEOUT 60)
endfunction()

# Adds every immediate subdirectory of the current source dir that has a CMakeLists.txt, sorted,
# so a new module or test folder plugs in without editing a shared list.
function(ddl_add_subdirectories)
  file(GLOB children LIST_DIRECTORIES true RELATIVE ${CMAKE_CURRENT_SOURCE_DIR}
       ${CMAKE_CURRENT_SOURCE_DIR}/*)
  list(SORT children)
  foreach(child IN LISTS children)
    if(IS_DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR}/${child}
       AND EXISTS ${CMAKE_CURRENT_SOURCE_DIR}/${child}/CMakeLists.txt)
      add_subdirectory(${child})
    endif()
  endforeach()
endfunction()

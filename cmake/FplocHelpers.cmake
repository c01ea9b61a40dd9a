# fploc_add_library(NAME SOURCES ... DEPS ...)  -> static library fploc_<NAME>, headers under include/
function(fploc_add_library NAME)
  cmake_parse_arguments(A "" "" "SOURCES;DEPS;PRIVATE_DEPS" ${ARGN})
  add_library(fploc_${NAME} STATIC ${A_SOURCES})
  target_include_directories(fploc_${NAME} PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)
  target_link_libraries(fploc_${NAME} PUBLIC ${A_DEPS} PRIVATE ${A_PRIVATE_DEPS})
endfunction()

# fploc_add_test(NAME SOURCES ... DEPS ... [LABELS ...]) -> gtest executable registered with ctest
function(fploc_add_test NAME)
  cmake_parse_arguments(A "" "" "SOURCES;DEPS;LABELS" ${ARGN})
  add_executable(${NAME} ${A_SOURCES})
  target_link_libraries(${NAME} PRIVATE ${A_DEPS} GTest::gtest GTest::gtest_main Threads::Threads)
  target_compile_definitions(${NAME} PRIVATE FPLOC_SHARED_DIR="${FPLOC_SHARED_DIR}"
                                               FPLOC_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
  add_test(NAME ${NAME} COMMAND ${NAME})
  # The test's scratch files (GoogleTest's TempDir(), which reads TEST_TMPDIR) in a folder of its own in the build tree:
  # fixed names directly in /tmp were shared by every checkout's test runs, and left behind.
  set(tmp "${CMAKE_BINARY_DIR}/test-tmp/${NAME}")
  file(MAKE_DIRECTORY "${tmp}")
  set_tests_properties(${NAME} PROPERTIES TIMEOUT 300 ENVIRONMENT "TEST_TMPDIR=${tmp}")
  if(A_LABELS)
    set_tests_properties(${NAME} PROPERTIES LABELS "${A_LABELS}")
  endif()
endfunction()

# fploc_add_benchmark(NAME SOURCES ... DEPS ...) -> Google Benchmark executable (not a test)
function(fploc_add_benchmark NAME)
  cmake_parse_arguments(A "" "" "SOURCES;DEPS" ${ARGN})
  add_executable(${NAME} ${A_SOURCES})
  target_link_libraries(${NAME} PRIVATE ${A_DEPS} benchmark::benchmark Threads::Threads)
  target_compile_definitions(${NAME} PRIVATE FPLOC_SHARED_DIR="${FPLOC_SHARED_DIR}"
                                               FPLOC_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
endfunction()

# fploc_add_node(NAME SOURCES ... DEPS ...)
#   The sources define a node class and register it with FPLOC_REGISTER_NODE(name, Class).
#   Produces an OBJECT library fploc_node_<NAME> (linked into the composed `fploc-compose` process)
#   and an executable fploc-<NAME> whose main is the shared runtime main.
function(fploc_add_node NAME)
  cmake_parse_arguments(A "" "" "SOURCES;DEPS" ${ARGN})
  add_library(fploc_node_${NAME} OBJECT ${A_SOURCES})
  target_link_libraries(fploc_node_${NAME} PUBLIC fploc_runtime ${A_DEPS})
  add_executable(fploc-${NAME} ${PROJECT_SOURCE_DIR}/runtime/src/node_main.cpp)
  target_link_libraries(fploc-${NAME} PRIVATE fploc_node_${NAME} fploc_runtime ${A_DEPS})
  set_property(GLOBAL APPEND PROPERTY FPLOC_NODES ${NAME})
endfunction()

set(FPLOC_SHARED_DIR "${PROJECT_SOURCE_DIR}/../shared" CACHE PATH "Shared data folder (tests skip when absent)")

# fploc_add_netns_test(NAME [SERIAL] COMMAND cmd args...) -> a ctest that runs inside its own network
# namespace (scripts/netns-run: loopback only, multicast routed to lo), so processes talking LCM are
# isolated. SERIAL: a real-time pipeline of many processes — no other test runs at the same time (CPU
# starvation would make LCM drop whole scan messages, a property of the transport, not of the code).
function(fploc_add_netns_test NAME)
  cmake_parse_arguments(A "SERIAL" "TIMEOUT" "COMMAND;LABELS" ${ARGN})
  add_test(NAME ${NAME} COMMAND ${PROJECT_SOURCE_DIR}/scripts/netns-run ${A_COMMAND})
  if(NOT A_TIMEOUT)
    set(A_TIMEOUT 300)
  endif()
  set_tests_properties(${NAME} PROPERTIES TIMEOUT ${A_TIMEOUT}
    ENVIRONMENT "FPLOC_BUILD_DIR=${CMAKE_BINARY_DIR};FPLOC_ROOT=${PROJECT_SOURCE_DIR};FPLOC_SHARED_DIR=${FPLOC_SHARED_DIR};PATH=${CMAKE_BINARY_DIR}/bin:$ENV{PATH}")
  if(A_SERIAL)  # parsed but never applied before: demo_live_swap ran beside other tests and lost scans (18 of 377)
    set_tests_properties(${NAME} PROPERTIES RUN_SERIAL TRUE)
  endif()
  if(A_LABELS)
    set_tests_properties(${NAME} PROPERTIES LABELS "${A_LABELS}")
  endif()
endfunction()

# ctest registration of the regression-tracking checks (perf/README.md), included from
# tests/CMakeLists.txt. Fast, and without a timing verdict on the code: they prove that
# the suites build and run, compare instruction counts with the committed baseline, and
# show that a deliberate slowdown is caught while a rerun is not.
find_program(VOLLEY_PYTHON3 python3)
if(NOT VOLLEY_PYTHON3)
  message(STATUS "python3 not found: perf tests not registered")
  return()
endif()

# The tools themselves (Mann-Whitney U, thresholds, compare's verdicts and exit codes).
add_test(NAME perf.tools COMMAND ${VOLLEY_PYTHON3} ${PROJECT_SOURCE_DIR}/perf/tests/test_tools.py)
set_tests_properties(perf.tools PROPERTIES LABELS perf TIMEOUT 60)

# The change-point detector on synthetic series and on a recorded history.
add_test(NAME perf.changepoint COMMAND ${VOLLEY_PYTHON3} ${PROJECT_SOURCE_DIR}/perf/tests/test_changepoint.py)
set_tests_properties(perf.changepoint PROPERTIES LABELS perf TIMEOUT 60)

# perf/ab.sh, the A/B of two volley executables: its refusals and its summary line.
add_test(NAME perf.ab_script COMMAND ${VOLLEY_PYTHON3} ${PROJECT_SOURCE_DIR}/perf/tests/check_ab_script.py
                                     $<TARGET_FILE:volley_cli>)
set_tests_properties(perf.ab_script PROPERTIES LABELS perf TIMEOUT 120)

# The rest needs volley_bench (built when Google Benchmark is found; see the top level).
if(VOLLEY_BUILD_BENCH AND benchmark_FOUND)
  set(bench $<TARGET_FILE:volley_bench>)
  add_test(NAME perf.suites_run COMMAND ${VOLLEY_PYTHON3} ${PROJECT_SOURCE_DIR}/perf/tests/check_suites_run.py ${bench})
  add_test(NAME perf.icount_vs_baseline
           COMMAND ${VOLLEY_PYTHON3} ${PROJECT_SOURCE_DIR}/perf/tests/check_icount_baseline.py ${bench})
  add_test(NAME perf.gbench_compare
           COMMAND ${VOLLEY_PYTHON3} ${PROJECT_SOURCE_DIR}/perf/tests/check_gbench_compare.py ${bench})
  add_test(NAME perf.synthetic_regression
           COMMAND ${VOLLEY_PYTHON3} ${PROJECT_SOURCE_DIR}/perf/tests/check_synthetic_regression.py ${bench})
  set_tests_properties(perf.suites_run perf.icount_vs_baseline perf.gbench_compare perf.synthetic_regression PROPERTIES
    LABELS perf TIMEOUT 120 SKIP_RETURN_CODE 77)
  # The timing half of the synthetic regression runs alone, so the rest of ctest -j does
  # not compete with it for the cores.
  set_tests_properties(perf.synthetic_regression PROPERTIES RUN_SERIAL TRUE)
endif()

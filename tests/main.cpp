// doctest entry point shared by every test executable. ctest runs each case on its own
// (doctest_discover_tests registers `--test-case=<name>`); a name the registration
// mangles (CMake splits names at ';') then matches no case, and doctest alone would
// report success for a run of nothing. So a run filtered by name that ran no case fails.
#define DOCTEST_CONFIG_IMPLEMENT
#include <doctest/doctest.h>

#include <cstdio>
#include <cstring>

#include "core/tsan_one_thread.h"  // (ThreadSanitizer build only)

namespace {

int g_cases_started = 0;

/// Counts the test cases that start (a listener: the chosen reporter still reports).
struct CaseCounter : doctest::IReporter {
  explicit CaseCounter(const doctest::ContextOptions&) {}
  void report_query(const doctest::QueryData&) override {}
  void test_run_start() override {}
  void test_run_end(const doctest::TestRunStats&) override {}
  void test_case_start(const doctest::TestCaseData&) override { ++g_cases_started; }
  void test_case_reenter(const doctest::TestCaseData&) override {}
  void test_case_end(const doctest::CurrentTestCaseStats&) override {}
  void test_case_exception(const doctest::TestCaseException&) override {}
  void subcase_start(const doctest::SubcaseSignature&) override {}
  void subcase_end() override {}
  void log_assert(const doctest::AssertData&) override {}
  void log_message(const doctest::MessageData&) override {}
  void test_case_skipped(const doctest::TestCaseData&) override {}
};

REGISTER_LISTENER("case_counter", 1, CaseCounter);

bool filtered_by_name(int argc, char** argv) {
  for (int i = 1; i < argc; ++i)
    if (std::strncmp(argv[i], "--test-case=", 12) == 0 || std::strncmp(argv[i], "-tc=", 4) == 0) return true;
  return false;
}

}  // namespace

int main(int argc, char** argv) {
  doctest::Context context(argc, argv);
  const int result = context.run();
  if (context.shouldExit()) return result;  // --list-test-cases and the like
  if (filtered_by_name(argc, argv) && g_cases_started == 0) {
    std::fprintf(stderr, "no test case matches the --test-case filter (a name the registration mangled?)\n");
    return 1;
  }
  return result;
}

#pragma once
// Scratch files for the tests.

#include <gtest/gtest.h>
#include <unistd.h>

#include <string>

namespace fp::test {

/// A path in the test temp directory private to the running test and process: ctest runs the tests of one
/// suite as parallel processes (and a developer's run may overlap a CI run), so a name shared by two tests of
/// a fixture lets one test's TearDown delete or rewrite the other's file mid-read.
inline std::string tempPath(const std::string& name) {
  const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string test =
      info ? std::string(info->test_suite_name()) + "_" + info->name() : std::string("no_test");
  for (char& c : test)
    if (c == '/')
      c = '_';  // parametrised suites are named "Prefix/Suite"
  std::string dir = ::testing::TempDir();
  if (!dir.empty() && dir.back() != '/')
    dir += '/';
  return dir + "fp_" + test + "_" + std::to_string(::getpid()) + "_" + name;
}

}  // namespace fp::test

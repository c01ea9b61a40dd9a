#pragma once
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace fploc::os1::test {
inline std::string ouster_dir() { return std::string(FPLOC_SHARED_DIR) + "/data/ouster"; }
inline bool have_shared() { return std::filesystem::exists(ouster_dir()); }
#define FPLOC_REQUIRE_SHARED() \
  if (!::fploc::os1::test::have_shared()) GTEST_SKIP() << "no ../shared/data"
}  // namespace fploc::os1::test

#pragma once
// Shared by the test suites: does a call reject a setting with a ddl::ConfigError that names it?
// Include as "config_error_check.h" (cmake/DdlModule.cmake puts tests/common on every test's
// include path).

#include <gtest/gtest.h>

#include <string>
#include <utility>

#include "ddl/core/error.h"

namespace ddl::test_support {

/// Success when `fn()` throws a ddl::ConfigError whose message contains `text` (a key such as
/// "dynamic.memory.max_age_frames", or a value it quotes); a failure that says what happened
/// otherwise. Other exceptions propagate, so the test fails with them. Use as
/// EXPECT_TRUE(throws_config_error_naming([&] { config.validate(); }, "key")).
template <typename Fn>
::testing::AssertionResult throws_config_error_naming(Fn&& fn, const std::string& text) {
  try {
    fn();
  } catch (const ConfigError& e) {
    if (std::string(e.what()).find(text) != std::string::npos) {
      return ::testing::AssertionSuccess();
    }
    return ::testing::AssertionFailure()
           << "the ConfigError does not name '" << text << "': " << e.what();
  }
  return ::testing::AssertionFailure() << "no ConfigError (expected one naming '" << text << "')";
}

/// Success when `fn()` throws a ddl::ConfigError for exactly `key` (ConfigError::for_key quotes
/// it: "configuration key 'tracking.orb.num_levels': ..."), so a longer key that merely contains
/// it does not pass.
template <typename Fn>
::testing::AssertionResult throws_config_error_for_key(Fn&& fn, const std::string& key) {
  return throws_config_error_naming(std::forward<Fn>(fn), "'" + key + "'");
}

}  // namespace ddl::test_support

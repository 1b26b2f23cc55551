// The InputError a loader throws, for tests of bad input: refusal(load) runs `load` and returns
// its InputError; a test failure (and an error naming nothing) when it accepts.
//
//   const InputError e = test::refusal([&] { load_friction_log(file); });
//   EXPECT_EQ(e.line(), 12);
//   EXPECT_TRUE(test::says(e, "--duplicate-times average"));
#pragma once

#include <gtest/gtest.h>

#include <string>
#include <string_view>

#include "lmcal/error.hpp"

namespace lmcal::test {

template <typename Load>
InputError refusal(Load&& load) {
  try {
    load();
  } catch (const InputError& e) {
    return e;
  }
  ADD_FAILURE() << "accepted: expected an InputError";
  return InputError("", 0, 0, "(accepted)");
}

// Whether the error's message holds `text` (the message shown when it does not).
inline ::testing::AssertionResult says(const InputError& e, std::string_view text) {
  if (std::string_view(e.what()).find(text) != std::string_view::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "'" << e.what() << "' does not say '" << text << "'";
}

}  // namespace lmcal::test

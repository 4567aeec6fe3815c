// The message of the quijibo::Error a call throws, for tests that check what an error says.
#pragma once
#include <gtest/gtest.h>

#include <string>

#include "util/error.h"

namespace quijibo::testing {

// Calls f; returns the what() of the quijibo::Error it throws, or records a test failure and
// returns "" when it throws none (other exceptions pass through).
template <class F>
std::string ThrownMessage(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "no quijibo::Error thrown";
  return "";
}

}  // namespace quijibo::testing

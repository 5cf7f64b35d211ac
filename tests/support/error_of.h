#pragma once
// The message of a thrown error, so a test checks what it says and not only that it threw.

#include <exception>
#include <functional>
#include <string>

namespace graspbed::test_support {

/// what() of the `Error` that `action` throws, or "(no error)" when it throws none. An exception of
/// any other type propagates and fails the test, so ErrorOf<std::invalid_argument> also checks the
/// type of the error.
template <typename Error = std::exception>
std::string ErrorOf(const std::function<void()>& action) {
  try {
    action();
  } catch (const Error& error) {
    return error.what();
  }
  return "(no error)";
}

}  // namespace graspbed::test_support

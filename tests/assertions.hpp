#pragma once
// Shared by the test executables: an assertion on the error a call raises.

#include <gtest/gtest.h>

#include <exception>
#include <initializer_list>
#include <string>
#include <utility>
#include <vector>

namespace drench::test {

/// Passes when `function` throws exactly an `Exception` whose message contains every string of `expected`;
/// on failure the actual message is shown, which is most of the point of the tests that use it.
template <class Exception, class Function>
testing::AssertionResult throws_containing(Function&& function, const std::vector<std::string>& expected) {
  try {
    function();
  } catch (const Exception& e) {
    const std::string message = e.what();
    for (const std::string& part : expected) {
      if (message.find(part) == std::string::npos) {
        return testing::AssertionFailure()
               << "message \"" << message << "\" does not contain \"" << part << "\"";
      }
    }
    return testing::AssertionSuccess();
  } catch (const std::exception& e) {
    return testing::AssertionFailure() << "threw another exception type: " << e.what();
  }
  return testing::AssertionFailure() << "did not throw";
}

/// The same with the parts in braces: {"a", "b"}.
template <class Exception, class Function>
testing::AssertionResult throws_containing(Function&& function, std::initializer_list<std::string> expected) {
  return throws_containing<Exception>(std::forward<Function>(function), std::vector<std::string>(expected));
}

/// The same with one expected part.
template <class Exception, class Function>
testing::AssertionResult throws_containing(Function&& function, const std::string& expected) {
  return throws_containing<Exception>(std::forward<Function>(function), std::vector<std::string>{expected});
}

}  // namespace drench::test

#pragma once
// What a call throws, as text: the tests of every reader assert that its errors name the file,
// the field and the fault, and all need "run this, give me the message".

#include <string>
#include <string_view>
#include <utility>

namespace concert {

/// The what() of the `Error` that `f()` throws; `none` if it returns normally. Exceptions of
/// other types pass through.
template <class Error, class F>
std::string error_text(F&& f, std::string_view none = "(no error)") {
  try {
    std::forward<F>(f)();
  } catch (const Error& e) {
    return e.what();
  }
  return std::string(none);
}

}  // namespace concert

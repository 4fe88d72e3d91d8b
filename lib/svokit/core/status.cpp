#include "svokit/core/status.hpp"

namespace svokit {

Status Status::WithContext(const std::string& context) const {
  // A failed write names its output already; the input's name in front would mislead.
  if (ok() || context.empty() || code_ == StatusCode::kCannotWrite) return *this;
  return {code_, context + ": " + message_};
}

}  // namespace svokit

#include "svokit/core/status.hpp"

namespace svokit {

Status Status::WithContext(const std::string& context) const {
  if (ok() || context.empty()) return *this;
  return {code_, context + ": " + message_};
}

}  // namespace svokit

#pragma once
// Errors are values: a library call returns a Status (or StatusOr<T>) with a one-line message; apps
// turn it into one line on stderr and an exit code.

#include <new>
#include <string>
#include <utility>
#include <variant>

#include <fmt/format.h>

namespace svokit {

/// Exit-code-compatible error classes: the apps' exit code is the numeric value (the table is in
/// README.md, "Exit codes").
enum class StatusCode : int {
  kOk = 0,
  kCheckFailed = 1,  ///< a validation found problems
  kBadInput = 2,     ///< unreadable / malformed input, impossible options
  kInternal = 3,     ///< a bug
  kCannotWrite = 4,  ///< the output cannot be written: disk full, permission, read-only, I/O error
  kOutOfMemory = 5,  ///< an allocation or a memory mapping was refused
};

class [[nodiscard]] Status {
 public:
  Status() = default;
  Status(StatusCode code, std::string message) : code_(code), message_(std::move(message)) {}

  static Status Ok() { return {}; }
  template <class... Args>
  static Status BadInput(fmt::format_string<Args...> f, Args&&... args) {
    return {StatusCode::kBadInput, fmt::format(f, std::forward<Args>(args)...)};
  }
  template <class... Args>
  static Status CheckFailed(fmt::format_string<Args...> f, Args&&... args) {
    return {StatusCode::kCheckFailed, fmt::format(f, std::forward<Args>(args)...)};
  }
  template <class... Args>
  static Status CannotWrite(fmt::format_string<Args...> f, Args&&... args) {
    return {StatusCode::kCannotWrite, fmt::format(f, std::forward<Args>(args)...)};
  }
  template <class... Args>
  static Status OutOfMemory(fmt::format_string<Args...> f, Args&&... args) {
    return {StatusCode::kOutOfMemory, fmt::format(f, std::forward<Args>(args)...)};
  }
  template <class... Args>
  static Status Internal(fmt::format_string<Args...> f, Args&&... args) {
    return {StatusCode::kInternal, fmt::format(f, std::forward<Args>(args)...)};
  }

  bool ok() const { return code_ == StatusCode::kOk; }
  StatusCode code() const { return code_; }
  const std::string& message() const { return message_; }
  int exit_code() const { return static_cast<int>(code_); }

  /// The same status with "context: " in front of the message (e.g. the input's name), except for
  /// kCannotWrite, whose message starts with the output's path.
  Status WithContext(const std::string& context) const;

 private:
  StatusCode code_ = StatusCode::kOk;
  std::string message_;
};

/// Memory that ran out where a Status cannot be returned (a constructor, a callback), with the
/// Status's message: a std::bad_alloc, so code that only knows those still releases what it holds.
class OutOfMemoryError : public std::bad_alloc {
 public:
  explicit OutOfMemoryError(std::string message) : message_(std::move(message)) {}
  const char* what() const noexcept override { return message_.c_str(); }

 private:
  std::string message_;
};

/// A value or the Status explaining why there is none.
template <class T>
class [[nodiscard]] StatusOr {
 public:
  StatusOr(T value) : v_(std::move(value)) {}         // NOLINT(google-explicit-constructor)
  StatusOr(Status status) : v_(std::move(status)) {}  // NOLINT(google-explicit-constructor)

  bool ok() const { return std::holds_alternative<T>(v_); }
  const Status& status() const {
    static const Status kOk;
    return ok() ? kOk : std::get<Status>(v_);
  }
  T& value() & { return std::get<T>(v_); }
  const T& value() const& { return std::get<T>(v_); }
  T&& value() && { return std::get<T>(std::move(v_)); }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }
  T& operator*() & { return value(); }
  const T& operator*() const& { return value(); }

 private:
  std::variant<T, Status> v_;
};

}  // namespace svokit

/// Returns from the enclosing function if `expr` (a Status) is not ok.
#define SVOKIT_RETURN_IF_ERROR(expr)         \
  do {                                       \
    ::svokit::Status _svokit_st = (expr);    \
    if (!_svokit_st.ok()) return _svokit_st; \
  } while (false)

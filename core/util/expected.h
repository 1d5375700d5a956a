// A value or an error message, for bad input that callers must handle (CONVENTIONS.md, tier 2).
// C++20 has no std::expected; this is the small subset we use.
#pragma once

#include <cstdlib>
#include <iostream>
#include <string>
#include <utility>
#include <variant>

namespace selfcal {

// An error that says where: file, field, byte offset, scan index.
struct Error {
  std::string message;
};

template <typename T>
class [[nodiscard]] Expected {
 public:
  Expected(T value) : storage_(std::move(value)) {}      // NOLINT(google-explicit-constructor)
  Expected(Error error) : storage_(std::move(error)) {}  // NOLINT(google-explicit-constructor)

  bool ok() const { return std::holds_alternative<T>(storage_); }
  explicit operator bool() const { return ok(); }

  const T& value() const& {
    CheckOk();
    return std::get<T>(storage_);
  }
  T& value() & {
    CheckOk();
    return std::get<T>(storage_);
  }
  T&& value() && {
    CheckOk();
    return std::get<T>(std::move(storage_));
  }
  const T& operator*() const& { return value(); }
  T& operator*() & { return value(); }
  const T* operator->() const { return &value(); }
  T* operator->() { return &value(); }

  const Error& error() const {
    if (ok()) {
      std::cerr << "selfcal: Expected::error() called on a value\n";
      std::abort();
    }
    return std::get<Error>(storage_);
  }

 private:
  void CheckOk() const {
    if (!ok()) {
      // Programmer error: the caller did not check. Abort with the message (tier 1).
      std::cerr << "selfcal: Expected::value() called on an error: "
                << std::get<Error>(storage_).message << "\n";
      std::abort();
    }
  }
  std::variant<T, Error> storage_;
};

// Success or an error, for operations without a value.
struct Ok {};
using Status = Expected<Ok>;
inline Status OkStatus() { return Ok{}; }

}  // namespace selfcal

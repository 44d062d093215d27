// What a physics operation reports: ok, or a message saying what failed ("chain.links = 0: must
// be an integer in [1, 4096]"). Physics never prints; the layer above shows the message. An ok
// Status holds an empty string and so allocates nothing: the step returns it on every call, and
// a steady step allocates nothing (tests/physics/step_allocation_test.cpp).
#pragma once

#include <string>
#include <utility>

namespace ponyhop {

class [[nodiscard]] Status {
 public:
  Status() = default;  // ok
  static Status error(std::string message) { return Status(std::move(message)); }

  bool ok() const { return ok_; }
  const std::string& message() const { return message_; }  // "" when ok

 private:
  explicit Status(std::string message) : ok_(false), message_(std::move(message)) {}

  bool ok_ = true;
  std::string message_;
};

}  // namespace ponyhop

#pragma once
/// Error helpers. User input errors are exceptions with context; broken internal invariants abort.
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#include <fmt/format.h>

namespace rotorguard {

/// Always-on internal invariant check (never for user input): prints and aborts.
[[noreturn]] void InvariantFailure(const char* condition, const char* file, int line,
                                   const std::string& message);

#define RG_INVARIANT(cond, msg)                                                    \
  do {                                                                             \
    if (!(cond)) ::rotorguard::InvariantFailure(#cond, __FILE__, __LINE__, (msg)); \
  } while (false)

/// A parameter that violates a rule. `field()` is the parameter's key path as written in config
/// files ("mass_kg", "rotors.2.max_thrust_n"), so a loader can point at the file and line.
class ValidationError : public std::invalid_argument {
 public:
  ValidationError(std::string field, const std::string& message)
      : std::invalid_argument(message), field_(std::move(field)) {}
  const std::string& field() const { return field_; }

 private:
  std::string field_;
};

/// Throws ValidationError "<owner>::<field> = <value> is invalid; expected <rule>".
template <typename T>
[[noreturn]] void ThrowValidation(const std::string& owner, const std::string& field,
                                  const T& value, const std::string& expected) {
  throw ValidationError(field, fmt::format("{}::{} = {} is invalid; expected {}", owner, field,
                                           value, expected));
}

/// The message of the rule `validate` finds broken (it throws ValidationError), or nullopt: for a
/// solver that reports bad input in its summary rather than throwing.
template <typename F>
std::optional<std::string> BrokenRule(F&& validate) {
  try {
    validate();
  } catch (const ValidationError& e) {
    return e.what();
  }
  return std::nullopt;
}

/// Throws std::invalid_argument "<api>: <parameter> = <value> is invalid; expected <rule>".
template <typename T>
[[noreturn]] void ThrowInvalidArgument(const std::string& api, const std::string& parameter,
                                       const T& value, const std::string& expected) {
  throw std::invalid_argument(
      fmt::format("{}: {} = {} is invalid; expected {}", api, parameter, value, expected));
}

}  // namespace rotorguard

#include "rotorguard/control/active_set.h"

#include "rotorguard/core/error.h"

namespace rotorguard::control {

std::string_view ToString(QpStatus status) {
  switch (status) {
    case QpStatus::kNotSolved: return "not solved (Solve() was not called)";
    case QpStatus::kSolved: return "solved";
    case QpStatus::kMaxIterations: return "max iterations reached";
    case QpStatus::kInfeasible: return "infeasible";
    case QpStatus::kNumericalFailure: return "numerical failure";
  }
  return "unknown";
}

std::string_view ToString(QpStart start) {
  switch (start) {
    case QpStart::kCold: return "cold";
    case QpStart::kWarm: return "warm";
    case QpStart::kHot: return "hot";
  }
  return "unknown";
}

void ActiveSetOptions::Validate() const {
  if (!(feasibility_tolerance > 0.0) || !std::isfinite(feasibility_tolerance)) {
    ThrowValidation("ActiveSetOptions", "feasibility_tolerance", feasibility_tolerance, "a finite value > 0");
  }
  if (max_iterations < 1) ThrowValidation("ActiveSetOptions", "max_iterations", max_iterations, "a count >= 1");
}

}  // namespace rotorguard::control

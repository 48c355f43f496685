#include "rotorguard/sim/battery.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "rotorguard/core/key_ranges.h"

namespace rotorguard::sim {

void BatteryOptions::Validate() const { CheckDeclaredRanges("BatteryOptions", *this); }

Battery::Battery(const BatteryOptions& options, const vehicle::VehicleParams& vehicle)
    : options_(options), charge_(options.initial_charge) {
  options_.Validate();
  for (const vehicle::Rotor& r : vehicle.rotors) yaw_coefficient_m_.push_back(r.yaw_coefficient_m);
  voltage_v_ = options_.cells * OpenCircuitVoltagePerCell(charge_);
}

double Battery::OpenCircuitVoltagePerCell(double charge) {
  // A LiPo cell at rest, from empty to full in steps of 5 % of its charge.
  static constexpr std::array<double, 21> kVolts = {3.27, 3.61, 3.69, 3.71, 3.73, 3.75, 3.77, 3.79, 3.80, 3.82, 3.84,
                                                    3.85, 3.87, 3.91, 3.95, 3.98, 4.02, 4.08, 4.11, 4.15, 4.20};
  const double x = std::clamp(charge, 0.0, 1.0) * 20.0;
  const auto i = std::min(static_cast<std::size_t>(x), kVolts.size() - 2);
  return kVolts[i] + (x - static_cast<double>(i)) * (kVolts[i + 1] - kVolts[i]);
}

void Battery::Step(const RotorVector& thrust_n, const RotorVector& speed_rad_s, double dt_s) {
  if (!options_.fitted) return;
  double shaft_w = 0.0;
  for (std::size_t i = 0; i < yaw_coefficient_m_.size() && static_cast<Eigen::Index>(i) < thrust_n.size(); ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    shaft_w += yaw_coefficient_m_[i] * std::max(0.0, thrust_n[k]) * std::abs(speed_rad_s[k]);
  }
  const double power_w = shaft_w / options_.efficiency;
  const double e = options_.cells * OpenCircuitVoltagePerCell(charge_);
  const double r = options_.internal_resistance_ohm;
  const double discriminant = e * e - 4.0 * r * power_w;
  voltage_v_ = discriminant > 0.0 ? 0.5 * (e + std::sqrt(discriminant)) : 0.5 * e;
  current_a_ = discriminant > 0.0 ? power_w / voltage_v_ : (r > 0.0 ? e / (2.0 * r) : 0.0);
  charge_ = std::max(0.0, charge_ - current_a_ * dt_s / (options_.capacity_mah * 3.6));
}

double Battery::thrust_limit_ratio() const {
  if (!options_.fitted) return 1.0;
  const double v = voltage_v_ / options_.reference_voltage_v;
  return std::min(1.0, v * v);
}

}  // namespace rotorguard::sim

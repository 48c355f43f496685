#pragma once
/// The flight battery: a lithium-polymer pack of `cells` in series, its open-circuit voltage E a
/// function of the charge left (a LiPo cell's resting voltage, OpenCircuitVoltagePerCell) behind
/// an internal resistance R. The rotors draw the electrical power P = sum_i kappa_i T_i w_i / eta
/// (each rotor's shaft power is its drag torque, kappa_i T_i (the yaw coefficient of eq. 3), times
/// its speed; eta the motors' and ESCs' efficiency), so the terminal voltage is the larger root
/// of V^2 - E V + R P = 0,
///
///     V = (E + sqrt(E^2 - 4 R P)) / 2,   I = P / V,
///
/// (at E^2 < 4 R P the pack cannot deliver P: it gives its most, at V = E / 2). The charge falls
/// by I dt over the capacity. A motor's top speed is proportional to its voltage, so each rotor's
/// largest thrust scales with (V / V_ref)^2, V_ref the voltage at which the vehicle file's T_bar
/// holds (never above T_bar: the file's limit is the ESCs' and propellers' too).
#include "rotorguard/core/config_schema.h"
#include "rotorguard/core/messages.h"
#include "rotorguard/core/types.h"
#include "rotorguard/vehicle/vehicle_params.h"

namespace rotorguard::sim {

struct BatteryOptions {
  /// Whether the pack is simulated; without, the rotors' limits are the file's throughout.
  bool fitted = false;
  int cells = 4;                          ///< in series (the reference quadrotor's 4S)
  double capacity_mah = 1500.0;           ///< [mAh]
  double internal_resistance_ohm = 0.03;  ///< the pack's [ohm] (a 1500-mAh 4S pack of 100C class)
  double initial_charge = 1.0;            ///< the state of charge at the start, in (0, 1]
  /// The terminal voltage at which the vehicle file's T_bar holds [V] (a full 4S pack at hover).
  double reference_voltage_v = 16.0;
  double efficiency = 0.75;  ///< shaft power over electrical power (motors and ESCs)
  double rate_hz = 10.0;     ///< the voltage messages' rate, as a power module's [Hz]
  void Validate() const;
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("fitted", &fitted, {.meaning = "a battery pack whose voltage sags with its load and charge"});
    a->Visit("cells", &cells, {.meaning = "LiPo cells in series", .min = 1, .max = 14});
    a->Visit("capacity_mah", &capacity_mah, {.meaning = "[mAh]", .max = 1e6, .positive = true});
    a->Visit("internal_resistance_ohm", &internal_resistance_ohm,
             {.meaning = "the pack's internal resistance [Ω]", .min = 0.0, .max = 10.0});
    a->Visit("initial_charge", &initial_charge, {.meaning = "the state of charge at the start", .max = 1.0, .positive = true});
    a->Visit("reference_voltage_v", &reference_voltage_v,
             {.meaning = "the terminal voltage at which the vehicle file's max_thrust_n holds [V]", .max = 100.0,
              .positive = true});
    a->Visit("efficiency", &efficiency, {.meaning = "the rotors' shaft power over the electrical power", .max = 1.0, .positive = true});
    a->Visit("rate_hz", &rate_hz, {.meaning = "the voltage messages' rate [Hz]", .min = 0.1, .max = 1000.0});
  }
};

class Battery {
 public:
  /// `vehicle`: its rotors' yaw coefficients (the drag torque per thrust). Throws ValidationError
  /// on bad options.
  Battery(const BatteryOptions& options, const vehicle::VehicleParams& vehicle);

  /// A LiPo cell's resting voltage at `charge` in [0, 1] [V]: 3.27 V empty, 3.84 V at half, 4.20 V
  /// full (the hobby industry's table of resting voltages, linear between its 5 % points).
  static double OpenCircuitVoltagePerCell(double charge);

  /// The rotors at thrusts `thrust_n` and speeds `speed_rad_s` draw their power for `dt_s`: the
  /// terminal voltage and current at that load, and the charge spent.
  void Step(const RotorVector& thrust_n, const RotorVector& speed_rad_s, double dt_s);

  double voltage_v() const { return voltage_v_; }
  double current_a() const { return current_a_; }
  double charge() const { return charge_; }
  /// The factor on every rotor's T_bar now: min(1, (V / V_ref)^2); 1 when none is fitted.
  double thrust_limit_ratio() const;
  /// What a power module reports at t.
  BatteryStatus Status(TimeNs t_ns) const { return {t_ns, voltage_v_, current_a_}; }
  const BatteryOptions& options() const { return options_; }

 private:
  BatteryOptions options_;
  std::vector<double> yaw_coefficient_m_;
  double charge_ = 1.0;
  double voltage_v_ = 0.0;
  double current_a_ = 0.0;
};

}  // namespace rotorguard::sim

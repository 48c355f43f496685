#pragma once
/// A recovery parachute: the flight stack's release signal (RotorCommand::release_parachute, sent
/// on flight termination) reaches the ejector with the command it rides on; the canopy is out
/// `ejection_delay_s` later and fills over `inflation_time_s`, its drag area growing with the
/// square of the time since ejection (the canopy's mouth opens about linearly, its projected area
/// with the square: the filling-time form of Knacke, "Parachute Recovery Systems Design Manual",
/// 1992, ch. 5, with exponent 2):
///
///     C_D S(tau) = C_D S_0 min(1, tau / t_f)^2,   F = -1/2 rho C_D S |v - w| (v - w),
///
/// tau the time since ejection, v the vehicle's and w the air's velocity. The force acts at the
/// centre of gravity (the riser's moment, which turns the vehicle under the canopy, is neglected).
/// The descent speed under the full canopy is sqrt(2 m g / (rho C_D S_0)): 4.5 m/s for the reference
/// quadrotor (1.15 kg) with the default 0.9 m^2.
#include <optional>

#include "rotorguard/core/config_schema.h"
#include "rotorguard/core/types.h"
#include "rotorguard/vehicle/multirotor.h"

namespace rotorguard::sim {

struct ParachuteOptions {
  /// Whether the vehicle carries one; without, the release signal is still recorded.
  bool fitted = false;
  /// From the release signal acting to the canopy out of its container [s] (spring- or
  /// gas-ejected canopies of small multirotors: about 0.1 s).
  double ejection_delay_s = 0.1;
  /// From ejection to the full drag area [s] (a small canopy at a few m/s: 0.3-0.5 s).
  double inflation_time_s = 0.4;
  /// C_D S_0 of the open canopy [m^2] (a 0.9-m canopy with C_D ~ 1.4).
  double drag_area_m2 = 0.9;
  /// Of the air [kg/m^3] (sea level, ISA).
  double air_density_kg_m3 = 1.225;
  void Validate() const;
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("fitted", &fitted, {.meaning = "the vehicle carries a parachute the stack's release signal deploys"});
    a->Visit("ejection_delay_s", &ejection_delay_s,
             {.meaning = "from the release signal acting to the canopy out [s]", .min = 0.0, .max = 5.0});
    a->Visit("inflation_time_s", &inflation_time_s,
             {.meaning = "from ejection to the full drag area, which grows with the time squared [s]", .min = 0.0, .max = 10.0});
    a->Visit("drag_area_m2", &drag_area_m2, {.meaning = "C_D S of the open canopy [m²]", .max = 100.0, .positive = true});
    a->Visit("air_density_kg_m3", &air_density_kg_m3, {.meaning = "of the air [kg/m³]", .min = 0.5, .max = 1.5});
  }
};

class Parachute final : public vehicle::StateWrench {
 public:
  explicit Parachute(const ParachuteOptions& options);

  /// The release signal acts at t (the first time counts; later ones change nothing).
  void Release(TimeNs t_ns);
  /// The drag area for the step starting at t (held over the step: the canopy fills over tenths
  /// of a second, the step is a millisecond).
  void Update(TimeNs t_ns);
  /// C_D S at time t [m^2]: 0 before ejection or when none is fitted.
  double DragAreaAt(TimeNs t_ns) const;
  /// The canopy's drag at x, in the air `d->wind_W` (force world frame, at the centre of gravity).
  void AddTo(const vehicle::StateVector& x, vehicle::Disturbance* d) const override;

  /// When the release signal acted, if it did (fitted or not).
  std::optional<TimeNs> released_ns() const { return released_ns_; }
  double drag_area_m2() const { return drag_area_m2_; }
  const ParachuteOptions& options() const { return options_; }

 private:
  ParachuteOptions options_;
  std::optional<TimeNs> released_ns_;
  double drag_area_m2_ = 0.0;  // at the current step
};

}  // namespace rotorguard::sim

#pragma once
/// Wind: a constant mean plus first-order Gauss-Markov gusts on each axis.
#include <cstdint>

#include "rotorguard/core/config_schema.h"
#include "rotorguard/core/rng.h"
#include "rotorguard/core/types.h"

namespace rotorguard::sim {

struct WindOptions {
  Vector3 mean_m_s = Vector3::Zero();  ///< mean wind velocity, world frame [m/s]
  double gust_std_m_s = 0.0;           ///< stationary std of each gust component [m/s], >= 0
  double gust_time_constant_s = 1.0;   ///< correlation time of gusts [s], > 0
  void Validate() const;
  /// The keys of this struct in config files (core/config_schema.h).
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("mean_m_s", &mean_m_s,
             {.meaning = "mean wind, world frame [m/s]", .min = -kMaxSpeedMS, .max = kMaxSpeedMS});
    a->Visit("gust_std_m_s", &gust_std_m_s,
             {.meaning = "stationary std of each Gauss-Markov gust component [m/s]", .min = 0.0, .max = kMaxSpeedMS});
    a->Visit("gust_time_constant_s", &gust_time_constant_s,
             {.meaning = "the gusts' correlation time [s]", .max = kMaxTimeoutS, .positive = true});
  }
};

class WindModel {
 public:
  WindModel(const WindOptions& options, std::uint64_t seed);
  /// Advances the gust process by dt [s] and returns the wind velocity.
  const Vector3& Step(double dt);
  const Vector3& velocity() const { return velocity_; }

 private:
  WindOptions options_;
  Rng rng_;
  Vector3 gust_ = Vector3::Zero();
  Vector3 velocity_ = Vector3::Zero();
};

}  // namespace rotorguard::sim

#include "rotorguard/modular/assembly_astar.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <queue>
#include <unordered_map>

#include "rotorguard/core/error.h"
#include "rotorguard/core/math.h"

namespace rotorguard::modular {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

/// Node key: cell offsets from the start (16 bits each, biased) and the yaw bin.
using Key = std::uint64_t;
Key Pack(const Eigen::Vector3i& c, int bin) {
  const auto u = [](int v) { return static_cast<std::uint64_t>(v + 32768) & 0xffff; };
  return (u(c.x()) << 48) | (u(c.y()) << 32) | (u(c.z()) << 16) | static_cast<std::uint64_t>(bin);
}

struct Node {
  double g = std::numeric_limits<double>::infinity();
  Key parent = 0;
  bool has_parent = false;
  bool closed = false;
};

}  // namespace

double AttitudeObjective(const Assembly& assembly, const RotorVector& eta, double yaw_rad,
                         const Eigen::Vector2d& direction_W) {
  const Eigen::Vector2d d = direction_W.normalized();
  const Eigen::Vector2d lateral(-d.y(), d.x());
  const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
  double roll_span = 0.0, pitch_span = 0.0;
  for (int k = 0; k < assembly.vehicle.num_rotors(); ++k) {
    const Vector3& p = assembly.vehicle.rotors[static_cast<std::size_t>(k)].p_B;
    const Eigen::Vector2d p_W(c * p.x() - s * p.y(), s * p.x() + c * p.y());
    const double f_max = eta[k] * assembly.vehicle.rotors[static_cast<std::size_t>(k)].max_thrust_n;
    // tau_x+- are the sums of the positive and negative lateral arms times f_max, tau_y+- those of
    // the longitudinal arms (eq. 8): their spans are the sums of |arm| f_max.
    roll_span += std::abs(p_W.dot(lateral)) * f_max;
    pitch_span += std::abs(p_W.dot(d)) * f_max;
  }
  return roll_span - pitch_span;
}

std::vector<double> OptimalYaws(const Assembly& assembly, const RotorVector& eta, const Eigen::Vector2d& direction_W,
                                int yaw_bins) {
  std::vector<double> values(static_cast<std::size_t>(yaw_bins));
  double best = std::numeric_limits<double>::infinity();
  for (int b = 0; b < yaw_bins; ++b) {
    values[static_cast<std::size_t>(b)] = AttitudeObjective(assembly, eta, kTwoPi * b / yaw_bins, direction_W);
    best = std::min(best, values[static_cast<std::size_t>(b)]);
  }
  std::vector<double> yaws;
  for (int b = 0; b < yaw_bins; ++b) {
    if (values[static_cast<std::size_t>(b)] <= best + 1e-9) yaws.push_back(kTwoPi * b / yaw_bins);
  }
  return yaws;
}

void AssemblyAStarOptions::Validate() const {
  const auto require = [](bool ok, const char* field, double v, const char* rule) {
    if (!ok) ThrowValidation("AssemblyAStarOptions", field, v, rule);
  };
  require(std::isfinite(resolution_m) && resolution_m > 0.0, "resolution_m", resolution_m, "a cell edge > 0 m");
  require(yaw_bins >= 1 && yaw_bins <= 360, "yaw_bins", yaw_bins, "a count in [1, 360]");
  require(std::isfinite(z_min_m) && std::isfinite(z_max_m) && z_min_m <= z_max_m, "z_max_m", z_max_m,
          "a finite altitude >= z_min_m");
  require(std::isfinite(attitude_weight) && attitude_weight >= 0.0, "attitude_weight", attitude_weight, "a weight >= 0");
  require(std::isfinite(yaw_step_cost_m) && yaw_step_cost_m >= 0.0, "yaw_step_cost_m", yaw_step_cost_m, "a cost >= 0");
  require(max_expansions >= 1, "max_expansions", max_expansions, "a count >= 1");
}

const char* ToString(AssemblyPathStatus status) {
  switch (status) {
    case AssemblyPathStatus::kFound: return "found";
    case AssemblyPathStatus::kStartBlocked: return "start_blocked";
    case AssemblyPathStatus::kGoalBlocked: return "goal_blocked";
    case AssemblyPathStatus::kNoPath: return "no_path";
    case AssemblyPathStatus::kExpansionLimit: return "expansion_limit";
  }
  return "?";
}

bool FootprintCollides(const perception::VoxelMap& map, const Assembly& assembly, const AssemblyPose& pose) {
  const double c = std::cos(pose.yaw_rad), s = std::sin(pose.yaw_rad);
  for (const Vector3& u : assembly.unit_position_B) {
    const Vector3 p = pose.p_W + Vector3(c * u.x() - s * u.y(), s * u.x() + c * u.y(), u.z());
    if (!map.InWindow(p) || map.IsInflated(p)) return true;
  }
  return false;
}

AssemblyPath FindAssemblyPath(const perception::VoxelMap& map, const Assembly& assembly, const RotorVector& eta,
                              const AssemblyPose& start, const Vector3& goal, const AssemblyAStarOptions& o) {
  o.Validate();
  if (eta.size() != assembly.vehicle.num_rotors()) {
    ThrowInvalidArgument("FindAssemblyPath", "eta.size()", eta.size(),
                         fmt::format("{} rotors", assembly.vehicle.num_rotors()));
  }
  if (map.options().inflation_radius_m < assembly.unit_radius_m) {
    ThrowInvalidArgument("FindAssemblyPath", "map inflation_radius_m", map.options().inflation_radius_m,
                         fmt::format("at least the unit's collision radius {} m (the footprint is checked unit by unit "
                                     "on the inflated layer)", assembly.unit_radius_m));
  }
  AssemblyPath result;
  const double res = o.resolution_m;
  const auto bin_of = [&](double yaw) {
    const int b = static_cast<int>(std::lround(std::fmod(std::fmod(yaw, kTwoPi) + kTwoPi, kTwoPi) / kTwoPi * o.yaw_bins));
    return b % o.yaw_bins;
  };
  const auto yaw_of = [&](int bin) { return kTwoPi * bin / o.yaw_bins; };
  const auto position_of = [&](const Eigen::Vector3i& c) { return Vector3(start.p_W + c.cast<double>() * res); };
  const auto collides = [&](const Vector3& p, double yaw) {
    return p.z() < o.z_min_m || p.z() > o.z_max_m || FootprintCollides(map, assembly, {p, yaw});
  };
  const int start_bin = bin_of(start.yaw_rad);
  if (collides(start.p_W, yaw_of(start_bin))) {
    result.status = AssemblyPathStatus::kStartBlocked;
    return result;
  }
  const Eigen::Vector3i goal_cell = ((goal - start.p_W) / res).array().round().cast<int>();
  bool goal_free = false;
  for (int b = 0; b < o.yaw_bins && !goal_free; ++b) goal_free = !collides(position_of(goal_cell), yaw_of(b));
  if (!goal_free) {
    result.status = AssemblyPathStatus::kGoalBlocked;
    return result;
  }

  // Eq. (7) per direction of flight (the 26 moves' horizontal directions and the goal's), cached by
  // the direction's angle to 0.1 deg.
  std::map<long, std::vector<double>> optimal;
  const auto attitude_error = [&](const Eigen::Vector2d& direction, double yaw) {
    const long key = std::lround(std::atan2(direction.y(), direction.x()) * 1800.0 / std::numbers::pi);
    auto it = optimal.find(key);
    if (it == optimal.end()) it = optimal.emplace(key, OptimalYaws(assembly, eta, direction, o.yaw_bins)).first;
    double e = std::numbers::pi;
    for (const double y : it->second) e = std::min(e, std::abs(WrapAngle(y - yaw)));
    return e;
  };
  // The direction of flight into a node: its move's horizontal part, else towards the goal.
  const auto flight_direction = [&](const Vector3& from, const Vector3& to) {
    Eigen::Vector2d d = (to - from).head<2>();
    if (d.norm() < 1e-9) d = (goal - to).head<2>();
    if (d.norm() < 1e-9) d = Eigen::Vector2d::UnitX();
    return Eigen::Vector2d(d.normalized());
  };

  std::unordered_map<Key, Node> nodes;
  using Entry = std::pair<double, Key>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> open;
  const Eigen::Vector3i origin = Eigen::Vector3i::Zero();
  const Key start_key = Pack(origin, start_bin);
  nodes[start_key].g = 0.0;
  open.emplace((goal - start.p_W).norm(), start_key);
  const auto unpack = [](Key k, Eigen::Vector3i* c, int* bin) {
    *c = Eigen::Vector3i(static_cast<int>((k >> 48) & 0xffff) - 32768, static_cast<int>((k >> 32) & 0xffff) - 32768,
                         static_cast<int>((k >> 16) & 0xffff) - 32768);
    *bin = static_cast<int>(k & 0xffff);
  };
  while (!open.empty()) {
    const Key key = open.top().second;
    open.pop();
    Node& node = nodes[key];
    if (node.closed) continue;
    node.closed = true;
    Eigen::Vector3i cell;
    int bin = 0;
    unpack(key, &cell, &bin);
    if (cell == goal_cell) {
      std::vector<Key> chain = {key};
      while (nodes[chain.back()].has_parent) chain.push_back(nodes[chain.back()].parent);
      std::reverse(chain.begin(), chain.end());
      for (const Key k : chain) {
        Eigen::Vector3i c;
        int b = 0;
        unpack(k, &c, &b);
        result.poses.push_back({position_of(c), yaw_of(b)});
      }
      result.poses.front() = {start.p_W, yaw_of(start_bin)};
      if (!collides(goal, result.poses.back().yaw_rad)) result.poses.back().p_W = goal;
      for (std::size_t i = 1; i < result.poses.size(); ++i) {
        const AssemblyPose& a = result.poses[i - 1];
        const AssemblyPose& b = result.poses[i];
        result.length_m += (b.p_W - a.p_W).norm();
        result.attitude_deviation_rad += attitude_error(flight_direction(a.p_W, b.p_W), b.yaw_rad);
      }
      result.status = AssemblyPathStatus::kFound;
      return result;
    }
    if (++result.expansions > o.max_expansions) {
      result.status = AssemblyPathStatus::kExpansionLimit;
      return result;
    }
    const Vector3 p = position_of(cell);
    const double g = node.g;
    const auto relax = [&](const Eigen::Vector3i& next_cell, int next_bin, double step_cost) {
      const Key next = Pack(next_cell, next_bin);
      Node& n = nodes[next];
      if (n.closed || g + step_cost >= n.g) return;
      const Vector3 q = position_of(next_cell);
      const double yaw = yaw_of(next_bin);
      if (collides(q, yaw)) {
        n.closed = true;  // a blocked pose stays blocked: never looked at again
        return;
      }
      n.g = g + step_cost;
      n.parent = key;
      n.has_parent = true;
      // Algorithm 1, line 16: F = G + H + J_Phi (the attitude term steers, it is not accumulated).
      const double f = n.g + (goal - q).norm() + o.attitude_weight * attitude_error(flight_direction(p, q), yaw);
      open.emplace(f, next);
    };
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dz = -1; dz <= 1; ++dz) {
          if (dx == 0 && dy == 0 && dz == 0) continue;
          relax(cell + Eigen::Vector3i(dx, dy, dz), bin, res * std::sqrt(static_cast<double>(dx * dx + dy * dy + dz * dz)));
        }
      }
    }
    if (o.yaw_bins > 1) {
      relax(cell, (bin + 1) % o.yaw_bins, o.yaw_step_cost_m);
      relax(cell, (bin + o.yaw_bins - 1) % o.yaw_bins, o.yaw_step_cost_m);
    }
  }
  result.status = AssemblyPathStatus::kNoPath;
  return result;
}

}  // namespace rotorguard::modular

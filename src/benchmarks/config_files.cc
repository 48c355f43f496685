#include "rotorguard/benchmarks/config_files.h"

#include <fmt/format.h>

#include <algorithm>

#include "rotorguard/campaign_kinds/registry.h"
#include "rotorguard/campaign_kinds/scenario_sweep.h"
#include "rotorguard/campaign/campaign.h"
#include "rotorguard/campaign/registry.h"
#include "rotorguard/harness/assembly_mission.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/io/config_archive.h"
#include "rotorguard/io/config_node.h"

namespace rotorguard::benchmarks {

ValidationReport ValidateConfigFile(const std::string& path) {
  const io::ConfigDocument doc = io::ConfigDocument::LoadFile(path);
  const io::ConfigNode root = doc.root();
  const std::vector<std::string> keys = root.Keys();
  const auto has = [&](const char* k) { return std::find(keys.begin(), keys.end(), k) != keys.end(); };
  if (has("rotors") || has("mass_kg")) {
    const vehicle::VehicleParams v = harness::LoadVehicle(path);
    return {"vehicle", fmt::format("vehicle '{}': {} rotors, {:g} kg, thrust-to-weight {:.2f}", v.name, v.num_rotors(),
                                   v.mass_kg, v.total_max_thrust_n() / v.weight_n())};
  }
  if (has("unit") && has("spacing_m")) {
    const modular::Assembly a = harness::LoadAssembly(path);
    return {"assembly", fmt::format("assembly '{}': {} units, {} rotors, {:g} kg, thrust-to-weight {:.2f}", a.name,
                                    a.num_units, a.vehicle.num_rotors(), a.vehicle.mass_kg,
                                    a.vehicle.total_max_thrust_n() / a.vehicle.weight_n())};
  }
  if (has("bench") && !has("mission")) {
    const campaign::Campaign c = campaign::LoadCampaign(path, CampaignKinds());
    return {"campaign", fmt::format("campaign '{}': {} trials of benchmark {}, spec {}", c.name, c.trials,
                                    c.bench["name"].get<std::string>(), c.hash)};
  }
  if (has("scenario") && !has("mission")) {
    const CampaignSpec c = LoadCampaignSpec(path);
    return {"campaign", fmt::format("campaign '{}': {} trials of {} ({} grid key(s), {} random), spec {}", c.name,
                                    c.trials(), c.scenario, c.grid.size(), c.random.size(), c.hash)};
  }
  // A composite FDD thresholds file (a vehicle file's `fdd`): only the detector's keys.
  io::KeyNameCollector fdd_keys;
  fdd::CompositeFddOptions{}.Serialize(&fdd_keys);
  const auto is_fdd_key = [&](const std::string& k) {
    return std::find(fdd_keys.names().begin(), fdd_keys.names().end(), k) != fdd_keys.names().end();
  };
  if (!keys.empty() && std::all_of(keys.begin(), keys.end(), is_fdd_key)) {
    const fdd::CompositeFddOptions o = harness::LoadFddThresholds(path);
    return {"fdd thresholds",
            fmt::format("composite FDD thresholds: gamma_M {:g}, gamma_P {:g}, take-off {:g}", o.motor_index_threshold,
                        o.propeller_index_threshold, o.takeoff_index_threshold)};
  }
  if (has("mission") || has("vehicle") || has("assembly")) {
    harness::Scenario s = harness::LoadScenario(path);
    harness::PlanMission(&s);  // a mission that cannot be planned is an invalid file
    return {"scenario", fmt::format("scenario '{}': {} mission, {:g} s, {} fault(s), vehicle {}", s.name,
                                    ToName(s.mission_kind), s.duration_s, s.faults.size(), s.vehicle_file)};
  }
  root.Fail(
      "cannot tell the kind of this file; expected a scenario (with 'mission' and 'vehicle'), "
      "a vehicle (with 'mass_kg' and 'rotors') or composite FDD thresholds (only stack.composite_fdd's keys)");
}

}  // namespace rotorguard::benchmarks

#include <fmt/format.h>

#include <string>
#include <utility>
#include <vector>

#include "rotorguard/harness/scenario_keys.h"
#include "rotorguard/io/key_table.h"
#include "rotorguard/planning/references.h"

namespace rotorguard::harness {

namespace {

/// "### `section`" and the table of `keys`' rows, each key prefixed by `prefix`.
template <typename Keys>
std::string Section(const std::string& title, const std::string& prefix, Keys keys) {
  io::KeyTableWriter writer;
  keys.Serialize(&writer);
  return fmt::format("### {}\n\n{}\n", title, io::KeyTableMarkdown(writer.rows(), prefix));
}

/// The stack's keys as a table of its own scalars and one table per block (stack.nmpc, ...).
std::string StackSections(Scenario* d) {
  io::KeyTableWriter writer;
  StackKeys{d}.Serialize(&writer);
  std::vector<io::KeyRow> scalars;
  std::vector<std::pair<std::string, std::vector<io::KeyRow>>> blocks;  // in the order declared
  for (io::KeyRow row : writer.rows()) {
    const std::size_t end = row.key.find_first_of(".[");
    if (end == std::string::npos) {
      scalars.push_back(row);
      continue;
    }
    const std::string block = row.key.substr(0, end);
    if (blocks.empty() || blocks.back().first != block) blocks.emplace_back(block, std::vector<io::KeyRow>{});
    blocks.back().second.push_back(row);
  }
  std::string md = fmt::format("### `stack`\n\n{}\n", io::KeyTableMarkdown(scalars, "stack."));
  for (const auto& [block, rows] : blocks) {
    md += fmt::format("### `stack.{}`\n\n{}\n", block, io::KeyTableMarkdown(rows, "stack."));
  }
  return md;
}

template <typename Options>
std::string MissionSection(MissionKind kind, Options options) {
  const std::string type = ToName(kind);
  return Section(fmt::format("`mission` with `type: {}`", type), "mission.", options);
}

}  // namespace

std::string ScenarioKeyTables() {
  Scenario d;  // every default, as a scenario without the key has it
  std::string md;
  md += Section("The top level", "", HeaderKeys{&d, ""});
  md += Section("`initial`", "initial.", InitialKeys{&d});
  md += Section("`world`", "world.", d.world);
  md += Section("`sim`", "sim.", SimKeys{&d});
  md += Section("`sensors`", "sensors.", SensorsKeys{&d.sim});
  md += Section("`wind`", "wind.", d.sim.wind);
  md += MissionSection(MissionKind::kHover, planning::HoverOptions{});
  md += MissionSection(MissionKind::kTakeoff, planning::TakeoffOptions{});
  md += MissionSection(MissionKind::kLemniscate, planning::LemniscateOptions{});
  md += MissionSection(MissionKind::kCircle, planning::CircleOptions{});
  md += MissionSection(MissionKind::kWaypoints, planning::WaypointOptions{});
  md += MissionSection(MissionKind::kNavigate, NavigateSpec{});
  md += MissionSection(MissionKind::kAssemblyPlan, AssemblyPlanSpec{});
  md += StackSections(&d);
  md += Section("`metrics`", "metrics.", MetricsKeys{&d});
  return md;
}

std::string VehicleKeyTable() {
  io::KeyTableWriter writer;
  vehicle::VehicleParams defaults;
  defaults.Serialize(&writer);
  return io::KeyTableMarkdown(writer.rows(), "");
}

}  // namespace rotorguard::harness

#include <fmt/format.h>

#include <string>
#include <utility>
#include <vector>

#include "rotorguard/harness/scenario_keys.h"
#include "rotorguard/io/key_table.h"
#include "rotorguard/planning/references.h"

namespace rotorguard::harness {

namespace {

/// The rows of `keys`.
template <typename Keys>
std::vector<io::KeyRow> RowsOf(Keys keys) {
  io::KeyTableWriter writer;
  keys.Serialize(&writer);
  return writer.rows();
}

/// The section titled `title` of `keys`, each key prefixed by `prefix`.
template <typename Keys>
KeyTableSection Section(const std::string& title, const std::string& prefix, Keys keys) {
  return {title, prefix, RowsOf(keys)};
}

/// The stack's keys as a section of its own scalars and one section per block (stack.nmpc, ...).
void AddStackSections(Scenario* d, std::vector<KeyTableSection>* sections) {
  KeyTableSection scalars{"`stack`", "stack.", {}};
  std::vector<KeyTableSection> blocks;  // in the order declared
  for (io::KeyRow row : RowsOf(StackKeys{d})) {
    const std::size_t end = row.key.find_first_of(".[");
    if (end == std::string::npos) {
      scalars.rows.push_back(row);
      continue;
    }
    const std::string block = row.key.substr(0, end);
    const std::string title = fmt::format("`stack.{}`", block);
    if (blocks.empty() || blocks.back().title != title) blocks.push_back({title, "stack.", {}});
    blocks.back().rows.push_back(row);
  }
  sections->push_back(std::move(scalars));
  sections->insert(sections->end(), blocks.begin(), blocks.end());
}

template <typename Options>
KeyTableSection MissionSection(MissionKind kind, Options options) {
  const std::string type = ToName(kind);
  return Section(fmt::format("`mission` with `type: {}`", type), "mission.", options);
}

}  // namespace

std::vector<KeyTableSection> ScenarioKeySections() {
  Scenario d;  // every default, as a scenario without the key has it
  std::vector<KeyTableSection> s;
  s.push_back(Section("The top level", "", HeaderKeys{&d, ""}));
  s.push_back(Section("`initial`", "initial.", InitialKeys{&d}));
  s.push_back(Section("`world`", "world.", d.world));
  s.push_back(Section("`sim`", "sim.", SimKeys{&d}));
  s.push_back(Section("`sensors`", "sensors.", SensorsKeys{&d.sim}));
  s.push_back(Section("`wind`", "wind.", d.sim.wind));
  s.push_back(MissionSection(MissionKind::kHover, planning::HoverOptions{}));
  s.push_back(MissionSection(MissionKind::kTakeoff, planning::TakeoffOptions{}));
  s.push_back(MissionSection(MissionKind::kLand, planning::LandingOptions{}));
  s.push_back(MissionSection(MissionKind::kLemniscate, planning::LemniscateOptions{}));
  s.push_back(MissionSection(MissionKind::kCircle, planning::CircleOptions{}));
  s.push_back(MissionSection(MissionKind::kWaypoints, planning::WaypointOptions{}));
  s.push_back(MissionSection(MissionKind::kNavigate, NavigateSpec{}));
  s.push_back(MissionSection(MissionKind::kAssemblyPlan, AssemblyPlanSpec{}));
  AddStackSections(&d, &s);
  s.push_back(Section("`metrics`", "metrics.", MetricsKeys{&d}));
  return s;
}

std::string ScenarioKeyTables() {
  std::string md;
  for (const KeyTableSection& s : ScenarioKeySections()) {
    md += fmt::format("### {}\n\n{}\n", s.title, io::KeyTableMarkdown(s.rows, s.prefix));
  }
  return md;
}

std::vector<io::KeyRow> VehicleKeyRows() { return RowsOf(vehicle::VehicleParams{}); }

std::string VehicleKeyTable() { return io::KeyTableMarkdown(VehicleKeyRows(), ""); }

}  // namespace rotorguard::harness

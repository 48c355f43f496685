#include "rotorguard/campaign/registry.h"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <stdexcept>

#include "rotorguard/io/files.h"

namespace rotorguard::campaign {

namespace fs = std::filesystem;

void CampaignRegistry::Add(CampaignKind kind) {
  if (Find(kind.name) != nullptr) {
    throw std::logic_error(fmt::format("CampaignRegistry::Add: kind '{}' is already registered", kind.name));
  }
  kinds_.push_back(std::move(kind));
}

const CampaignKind* CampaignRegistry::Find(const std::string& name) const {
  const auto it = std::find_if(kinds_.begin(), kinds_.end(), [&](const CampaignKind& k) { return k.name == name; });
  return it == kinds_.end() ? nullptr : &*it;
}

std::vector<std::string> CampaignRegistry::names() const {
  std::vector<std::string> names;
  for (const CampaignKind& k : kinds_) {
    if (!k.name.empty()) names.push_back(k.name);
  }
  return names;
}

Campaign LoadCampaign(const std::string& path, const CampaignRegistry& kinds) {
  const io::ConfigDocument doc = io::ConfigDocument::LoadFile(path);
  const io::ConfigNode root = doc.root();
  // Keys() does not mark `bench` as read: a spec without it is the unnamed kind's to judge whole.
  const std::vector<std::string> keys = root.Keys();
  if (std::find(keys.begin(), keys.end(), "bench") == keys.end()) {
    const CampaignKind* unnamed = kinds.Find("");
    if (unnamed == nullptr) root.Fail("expected the key 'bench' naming the campaign's kind");
    return unnamed->load(root, path);
  }
  const io::ConfigNode bench = root.Required("bench");
  const std::string name = root.Required("name").AsString();
  if (!IsValidCampaignName(name)) {
    root.FailAt("name", fmt::format("'{}' is invalid; expected letters, digits, '_', '.' or '-' (it names files and "
                                    "Slurm jobs)",
                                    name));
  }
  const CampaignKind& kind = *kinds.Find(bench.AsEnum(kinds.names()));
  Campaign c = kind.load(root, path);
  root.RejectUnknownKeys();
  c.name = name;
  c.file = path;
  return c;
}

BenchReport CampaignResult(const nlohmann::json& bench, const std::vector<nlohmann::json>& records,
                           const CampaignRegistry& kinds) {
  const std::string name = bench.value("name", "");
  const CampaignKind* kind = name.empty() ? nullptr : kinds.Find(name);
  if (kind == nullptr || !kind->result) {
    std::vector<std::string> names = kinds.names();
    std::string expected = names.empty() ? "none" : names.back();
    if (names.size() > 1) {
      names.pop_back();
      expected = fmt::format("{} or {}", fmt::join(names, ", "), expected);
    }
    throw std::invalid_argument(fmt::format("benchmark '{}' is unknown; expected {}", name, expected));
  }
  return kind->result(bench.at("options"), records);
}

void WriteBenchFiles(const BenchReport& report, const std::string& dir) {
  io::WriteFileAtomically((fs::path(dir) / "bench.json").string(), report.result.dump(2) + "\n");
  io::WriteFileAtomically((fs::path(dir) / "bench.md").string(), report.markdown);
}

}  // namespace rotorguard::campaign

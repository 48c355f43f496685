// rotorguard._core's campaigns (docs/campaigns.md) and their statistics: records cross as JSON
// text, which the package parses. The campaign kinds come from their own library, without the
// benchmarks that are not campaigns.
#include <pybind11/stl.h>

#include <optional>
#include <string>
#include <vector>

#include "bindings.h"
#include "rotorguard/buildinfo/build_info.h"
#include "rotorguard/campaign/campaign.h"
#include "rotorguard/campaign/merge.h"
#include "rotorguard/campaign/statistics.h"
#include "rotorguard/campaign_kinds/registry.h"

namespace rotorguard::python {

void BindCampaigns(py::module_& m) {
  m.def("wilson_interval", &campaign::WilsonInterval, py::arg("successes"), py::arg("trials"),
        "The 95 % Wilson score interval (lo, hi) of `successes` in `trials` ((0, 1) for no trial)");
  m.def("mcnemar_exact_p", &campaign::McNemarExactP, py::arg("only_first"), py::arg("only_second"),
        "The exact McNemar test's two-sided p-value of a paired comparison's discordant pairs");

  m.def(
      "run_campaign",
      [](const std::string& spec, const std::optional<std::string>& out, int jobs, int shard_index, int shard_count,
         bool resume, double trial_timeout_factor) -> py::object {
        std::optional<std::vector<nlohmann::json>> records;
        {
          py::gil_scoped_release release;
          const campaign::Campaign campaign = campaign::LoadCampaign(spec, benchmarks::CampaignKinds());
          campaign::CampaignRunOptions o;
          o.out_dir = out.value_or("");
          o.jobs = jobs;
          o.shard = {shard_index, shard_count};
          o.resume = resume;
          o.trial_timeout_factor = trial_timeout_factor;
          o.version = buildinfo::ProgramVersion();
          records = campaign::RunCampaignRecords(campaign, o);
        }
        if (!records) return py::none();
        return py::str(nlohmann::json(*records).dump());
      },
      py::arg("spec"), py::arg("out"), py::arg("jobs"), py::arg("shard_index"), py::arg("shard_count"),
      py::arg("resume"), py::arg("trial_timeout_factor"));
  m.def(
      "read_campaign",
      [](const std::vector<std::string>& dirs) {
        nlohmann::json manifest;
        const std::vector<nlohmann::json> records = campaign::ReadCampaignRecords(dirs, &manifest);
        return py::make_tuple(nlohmann::json(records).dump(), manifest.dump());
      },
      py::arg("dirs"));
  m.def(
      "merge_campaign",
      [](const std::vector<std::string>& dirs, const std::string& out) {
        return campaign::MergeCampaign(dirs, out, benchmarks::CampaignKinds()).dump();
      },
      py::arg("dirs"), py::arg("out"));

}

}  // namespace rotorguard::python

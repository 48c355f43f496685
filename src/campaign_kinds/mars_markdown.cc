// bench mars's result as Markdown: the tables MarsResult computes, written for a terminal or a page.
#include <fmt/format.h>

#include <string>

#include "rotorguard/campaign_kinds/mars_bench.h"

namespace rotorguard::benchmarks {

namespace {
/// A table cell's note when some of its flights crashed: their error up to the crash, beside the
/// window's (where the wreck is held to the window's end).
std::string ToCrash(const nlohmann::json& row, const std::string& method) {
  const double to_crash = row.value(method + "_error_to_crash_m", 0.0);
  if (to_crash == row[method + "_error_m"].get<double>()) return "";
  return fmt::format("; {:.3f} m to the crash", to_crash);
}
}  // namespace

std::string MarsMarkdown(const nlohmann::json& r) {
  std::string s = fmt::format("Table I ({} assembly on the spiral, {} flights per cell: mean tracking RMSE, "
                              "success rate)\n\n",
                              r["assembly"].get<std::string>(), r["trials"].get<int>());
  s += "| case | without FTC | partial (eqs. 3-5) | full (eq. 6) | full / fault-free |\n|---|---|---|---|---|\n";
  for (const auto& row : r["table1"]) {
    const auto cell = [&](const char* m) {
      return fmt::format("{:.3f} m ({:.0f} %{})", row[std::string(m) + "_error_m"].get<double>(),
                         100.0 * row[std::string(m) + "_success_rate"].get<double>(), ToCrash(row, m));
    };
    const bool hover = row["hover_attainable"].get<bool>();  // a ratio only where the target applies
    s += fmt::format("| {}{} | {} | {} | {} | {} |\n", row["case"].get<std::string>(),
                     hover ? "" : " (cannot hover: beyond the rotors' reach)", cell("none"), cell("partial"),
                     cell("full"), hover ? fmt::format("{:.2f}", row["full_over_fault_free"].get<double>()) : "-");
  }
  s += r["alloc_us_mean"].is_null()
           ? std::string("\nallocation: the timing trial failed (see the campaign's errors)\n")
           : fmt::format("\nallocation ({} units, full reallocation with a dead unit): {:.1f} us mean, {:.1f} us p99\n",
                         r["alloc_units"].get<int>(), r["alloc_us_mean"].get<double>(), r["alloc_us_p99"].get<double>());
  if (!r["reconfig"].is_null()) {
    s += "\nSelf-reconfiguration (largest over the successful trials, their median in brackets; acceleration: the "
         "velocity's change over 20 ms)\n\n| switch | success | steady hover | separation | docking | "
         "unit's tilt |\n|---|---|---|---|---|---|\n";
    for (const char* v : {"prepared", "naive"}) {
      const nlohmann::json& x = r["reconfig"][v];
      const auto both = [&](const std::string& key, int digits) {
        return fmt::format("{:.{}f} ({:.{}f})", x[key].get<double>(), digits, x[key + "_median"].get<double>(), digits);
      };
      s += fmt::format("| {} | {:.0f} % | {} deg, {} m/s^2 | {} deg, {} m/s^2 | {} deg, {} m/s^2 | {} deg |\n", v,
                       100.0 * x["success_rate"].get<double>(), both("steady_max_attitude_deg", 2),
                       both("steady_max_accel_m_s2", 2), both("separation_max_attitude_deg", 2),
                       both("separation_max_accel_m_s2", 2), both("docking_max_attitude_deg", 2),
                       both("docking_max_accel_m_s2", 2), both("unit_max_tilt_deg", 1));
    }
  }
  if (!r["table2"].is_null()) {
    s += "\nTable II (each trial's start and goal moved by up to 0.1 m, planned by each method and flown with the "
         "full reallocation: mean tracking RMSE of the flights planned, success rate of all trials, plans made, "
         "the trajectory's mean duration; the improvement over the trials both planned)\n\n| shape | fault | "
         "baseline (SVSDF) | ours | improvement (trials) |\n|---|---|---|---|---|\n";
    for (const auto& row : r["table2"]) {
      // Where some drawn assemblies cannot hover at all, the success among those that can beside.
      const int hover_capable = row.value("hover_capable_trials", r["trials"].get<int>());
      const bool bounded = hover_capable < r["trials"].get<int>();
      const auto cell = [&](const std::string& m) {
        if (!row[m + "_planned"].get<bool>()) return "no plan: " + row[m + "_plan_failure"].get<std::string>();
        const nlohmann::json& capable = row[m + "_success_rate_hover_capable"];
        return fmt::format("{:.3f} m ({:.0f} %{}, planned {:.0f} %, {:.1f} s{})", row[m + "_error_m"].get<double>(),
                           100.0 * row[m + "_success_rate"].get<double>(),
                           bounded && !capable.is_null() ? fmt::format(", {:.0f} % where it can hover",
                                                                       100.0 * capable.get<double>())
                                                         : std::string(),
                           100.0 * row[m + "_plan_rate"].get<double>(), row[m + "_duration_s"].get<double>(),
                           ToCrash(row, m));
      };
      s += fmt::format("| {} | {}{} | {} | {} | {} ({}) |\n", row["shape"].get<std::string>(),
                       row["fault"].get<std::string>(),
                       bounded ? fmt::format(" (the drawn assembly cannot hover in {} of {} trials)",
                                             r["trials"].get<int>() - hover_capable, r["trials"].get<int>())
                               : std::string(),
                       cell("baseline"), cell("ours"),
                       row["improvement"].is_null() ? std::string("-")
                                                    : fmt::format("{:.1f} %", 100.0 * row["improvement"].get<double>()),
                       row["paired_trials"].get<int>());
    }
    const auto percent = [](const nlohmann::json& v) {
      return v.is_null() ? std::string("-") : fmt::format("{:.1f} %", 100.0 * v.get<double>());
    };
    s += fmt::format(
        "\naverage improvement {} (1 - mean ours / mean baseline, the paper's Average row; {} as the "
        "mean of the rows', {} with the errors to the crash); ours better in every row: {}\n",
        percent(r["table2_improvement_average"]), percent(r["table2_improvement_row_mean"]),
        percent(r["table2_improvement_average_to_crash"]),
        r["table2_ours_better_in_every_row"].get<bool>() ? "yes" : "no");
  }
  return s;
}

}  // namespace rotorguard::benchmarks

// rotorguard_flight_fuzz: valid scenarios, generated from the declared keys, flown by the CLI
// (docs/reliability.md, "Generated flights"). Each flight starts from a scenario of configs/
// (every mission kind, assemblies and navigation among them), sets 1-8 of the keys its blocks
// declare to values drawn inside their documented ranges (an end of the range a fifth of the
// time), switches enums (controller, FDD, estimator, ...), adds, re-times or drops faults of every
// kind, and lasts 1-3 s. A scenario that `validate` refuses is counted (a rule that couples keys)
// and not flown. Each accepted one is flown by `rotorguard run`, and it is a finding when:
//   - it runs past 100 times its simulated time (wall clock), or dies of a signal;
//   - it exits with a code other than 0, 1 (the mission failed) or 4 (infeasible): 2 or 3 after
//     `validate` accepted the file;
//   - an output is half-written (a temporary file left, report.html cut short) or unreadable
//     (summary.json, log.csv, sensors.csv read back as `report` and `fdd-calibrate` read them);
//   - a number in summary.json or in the report's data is not finite.
// The findings' scenarios are kept as flight-finding-SEED-N.yaml; the exit code is 1 when there is one.
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "fuzz_targets.h"
#include "rotorguard/benchmarks/config_files.h"
#include "rotorguard/benchmarks/fdd_calibration.h"
#include "rotorguard/harness/scenario_keys.h"
#include "rotorguard/io/config_node.h"
#include "rotorguard/record/flight_log.h"
#include "rotorguard/record/report.h"
#include "rotorguard/vehicle/faults.h"

namespace {

namespace fs = std::filesystem;
using rotorguard::io::KeyRow;

// The wall-clock bound of docs/reliability.md.
constexpr double kBudgetPerSimulatedSecond = 100.0;
constexpr const char* kUsage = "usage: rotorguard_flight_fuzz [--flights N] [--seed S] [--jobs J in [1, 64]]\n";

// A key that can be set: its full dotted path ("stack.nmpc.horizon_steps", "world.boxes[].size_m")
// and its declaration.
struct Key {
  std::string path;
  KeyRow row;
  std::string mission_type;  // the mission type whose section declares it, or empty
};

// Blocks a scenario may gain without changing what it flies (the others are used only when the
// base file has them: a `sensors.lidar` block turns the LiDAR on).
bool MayCreate(const std::string& block) {
  static const char* const kBlocks[] = {"initial",          "sim",  "sensors", "sensors.imu", "sensors.esc",
                                        "sensors.odometry", "wind", "metrics", "stack"};
  return std::find(std::begin(kBlocks), std::end(kBlocks), block) != std::end(kBlocks);
}

std::vector<Key> DeclaredKeys() {
  std::vector<Key> keys;
  for (const rotorguard::harness::KeyTableSection& s : rotorguard::harness::ScenarioKeySections()) {
    std::string type;
    if (const std::size_t at = s.title.find("type: "); at != std::string::npos) {
      type = s.title.substr(at + 6, s.title.find('`', at) - at - 6);
    }
    for (const KeyRow& row : s.rows) {
      const std::string path = s.prefix + row.key;
      if (row.count == 0 && row.choices.empty()) continue;  // text (a name, a file) and blocks
      if (path == "duration_s" || path == "seed" || path == "mission.type") continue;  // set below
      keys.push_back({path, row, type});
    }
  }
  return keys;
}

class Generator {
 public:
  explicit Generator(std::uint64_t seed) : rng_(seed) {}

  double Uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng_); }
  std::size_t Below(std::size_t n) { return std::uniform_int_distribution<std::size_t>(0, n - 1)(rng_); }
  bool Chance(double p) { return Uniform(0.0, 1.0) < p; }

  // A number inside the declared range [lo, hi] ((0, hi] when positive; hi excluded when open):
  // an end a fifth of the time, else uniform or, over a wide positive range, log-uniform.
  double Number(const rotorguard::KeyInfo& r, double cap, bool integer) {
    double lo = r.positive ? std::nextafter(0.0, 1.0) : r.min;
    double hi = std::min(r.max, cap);
    if (r.open_max) hi = std::nextafter(hi, lo);
    if (!std::isfinite(lo)) lo = -1e4;
    if (!std::isfinite(hi)) hi = 1e4;
    if (integer) {
      lo = std::ceil(lo);
      hi = std::floor(hi);
    }
    double v;
    if (Chance(0.2)) {
      v = Chance(0.5) ? lo : hi;
    } else if (lo >= 0.0 && hi > 1e3 * std::max(lo, 1e-12) && Chance(0.6)) {
      const double a = std::log(std::max(lo, hi * 1e-9));
      v = std::exp(Uniform(a, std::log(hi)));
    } else {
      v = Uniform(lo, hi);
    }
    v = std::clamp(v, lo, hi);
    return integer ? std::round(v) : v;
  }

  std::mt19937_64& rng() { return rng_; }

 private:
  std::mt19937_64 rng_;
};

// The map holding the key at `path` below `root` ("a.b[].c") and the key's name: blocks on the way
// are made where MayCreate allows, and a list's item is one of its items, drawn. False when the
// path does not exist and may not be made.
bool Resolve(YAML::Node root, const std::string& path, Generator* g, YAML::Node* parent, std::string* leaf) {
  YAML::Node node = root;
  std::string walked;
  std::size_t start = 0;
  while (true) {
    const std::size_t dot = path.find('.', start);
    std::string segment = path.substr(start, dot == std::string::npos ? std::string::npos : dot - start);
    if (dot == std::string::npos) {
      *parent = node;
      *leaf = segment;
      return node.IsMap() || node.IsNull();
    }
    const bool list = segment.size() > 2 && segment.ends_with("[]");
    if (list) segment.resize(segment.size() - 2);
    walked += (walked.empty() ? "" : ".") + segment;
    YAML::Node next = node[segment];
    if (list) {
      if (!next.IsSequence() || next.size() == 0) return false;
      next = next[g->Below(next.size())];
    } else if (!next.IsDefined() || next.IsNull()) {
      if (!MayCreate(walked)) return false;
      node[segment] = YAML::Node(YAML::NodeType::Map);
      next = node[segment];
    } else if (!next.IsMap()) {
      return false;  // a shorthand scalar (`planner: flatness`): its block's keys do not apply
    }
    node.reset(next);
    start = dot + 1;
  }
}

YAML::Node Value(const Key& k, const YAML::Node& current, double duration_s, Generator* g) {
  const KeyRow& r = k.row;
  if (!r.choices.empty()) return YAML::Node(r.choices[g->Below(r.choices.size())]);
  // Keys bounded by the flight's duration (the tables' range is the default flight's).
  const bool within_flight = r.rule.find("duration_s") != std::string::npos;
  const double cap = within_flight ? duration_s : std::numeric_limits<double>::infinity();
  const auto number = [&] { return g->Number(r.range, cap, r.integer); };
  if (r.count == 1) return YAML::Node(number());
  YAML::Node seq(YAML::NodeType::Sequence);
  if (r.count == -1) {  // a list of points: one of its points moved
    if (!current.IsSequence() || current.size() == 0) return YAML::Node();
    seq = YAML::Clone(current);
    YAML::Node point(YAML::NodeType::Sequence);
    for (int i = 0; i < 3; ++i) point.push_back(number());
    seq[g->Below(seq.size())] = point;
    return seq;
  }
  if (r.count == 9) {
    for (int i = 0; i < 3; ++i) {
      YAML::Node row(YAML::NodeType::Sequence);
      for (int j = 0; j < 3; ++j) row.push_back(number());
      seq.push_back(row);
    }
    return seq;
  }
  for (int i = 0; i < r.count; ++i) seq.push_back(number());
  return seq;
}

// The faults: re-timed into the flight, some dropped, some added of any kind.
void MutateFaults(YAML::Node root, double duration_s, Generator* g) {
  const auto& kinds = rotorguard::vehicle::kFaultKindNames;  // every kind a file can name
  YAML::Node faults = root["faults"];
  YAML::Node out(YAML::NodeType::Sequence);
  if (faults.IsSequence() && !g->Chance(0.2)) {
    for (YAML::Node f : faults) {
      if (f["onset"].IsMap() && f["onset"]["at_time_s"].IsDefined())
        f["onset"]["at_time_s"] = g->Uniform(0.0, duration_s);
      out.push_back(f);
    }
  }
  const int added = g->Chance(0.5) ? 1 + static_cast<int>(g->Below(2)) : 0;
  for (int i = 0; i < added; ++i) {
    YAML::Node f(YAML::NodeType::Map);
    f["rotor"] = static_cast<int>(g->Below(4));
    const std::string kind = kinds[g->Below(std::size(kinds))].name;
    f["kind"] = kind;
    if (kind == "loss_of_effectiveness") f["eta"] = g->Uniform(0.0, 1.0);
    f["onset"]["at_time_s"] = g->Uniform(0.0, duration_s);
    if (g->Chance(0.2)) {
      f["intermittent"]["on_s"] = g->Uniform(0.01, 1.0);
      f["intermittent"]["off_s"] = g->Uniform(0.01, 1.0);
    }
    out.push_back(f);
  }
  if (out.size() > 0) {
    root["faults"] = out;
  } else {
    root.remove("faults");
  }
}

struct Flight {
  int index = 0;
  std::string scenario, out_dir, base;
  double duration_s = 0.0;
  std::chrono::steady_clock::time_point start;
  pid_t pid = -1;
};

// Scenario `index`: drawn from a base of configs/scenarios, written into the scratch folder.
Flight DrawFlight(int index, const std::vector<std::string>& bases, const std::vector<Key>& keys,
                  const fs::path& scratch, Generator* g) {
  Flight f;
  f.index = index;
  f.base = bases[g->Below(bases.size())];
  YAML::Node root = YAML::LoadFile((scratch / "scenarios" / f.base).string());
  f.duration_s = g->Uniform(1.0, 3.0);
  root["duration_s"] = f.duration_s;
  root["seed"] = static_cast<std::uint64_t>(g->rng()() >> 1);
  const std::string mission = root["mission"]["type"] ? root["mission"]["type"].as<std::string>() : "";
  const int changes = 1 + static_cast<int>(g->Below(8));
  for (int c = 0; c < changes; ++c) {
    const Key& k = keys[g->Below(keys.size())];
    if (!k.mission_type.empty() && k.mission_type != mission) continue;
    YAML::Node parent;
    std::string leaf;
    if (!Resolve(root, k.path, g, &parent, &leaf)) continue;
    YAML::Node value = Value(k, parent[leaf], f.duration_s, g);
    if (value.IsDefined() && !value.IsNull()) parent[leaf] = value;
  }
  MutateFaults(root, f.duration_s, g);
  // Windows inside the flight (the metrics' keys are bounded by duration_s).
  for (const char* key : {"tracking_start_s", "tracking_end_s", "success_hold_s"}) {
    if (root["metrics"][key] && root["metrics"][key].as<double>() > f.duration_s) root["metrics"][key] = f.duration_s;
  }
  f.scenario = (scratch / "scenarios" / ("generated-" + std::to_string(f.index) + ".yaml")).string();
  YAML::Emitter emitter;
  emitter.SetDoublePrecision(17);
  emitter << root;
  std::ofstream(f.scenario) << emitter.c_str() << "\n";
  return f;
}

// Starts `rotorguard run` on the flight's scenario, its output silenced.
void Launch(Flight* f) {
  f->start = std::chrono::steady_clock::now();
  f->pid = fork();
  if (f->pid == 0) {
    const int null = open("/dev/null", O_WRONLY);
    dup2(null, STDOUT_FILENO);
    dup2(null, STDERR_FILENO);
    execl(ROTORGUARD_CLI, ROTORGUARD_CLI, "run", f->scenario.c_str(), "--out", f->out_dir.c_str(), "-q",
          static_cast<char*>(nullptr));
    _exit(127);  // exec failed
  }
}

// What is wrong with a finished flight's outputs, or empty.
std::string CheckOutputs(const Flight& f, int code) {
  if (code != 0 && code != 1 && code != 4) return "exit code " + std::to_string(code) + " after validate accepted";
  for (const auto& entry : fs::directory_iterator(f.out_dir)) {
    if (entry.path().filename().string().find(".tmp-") != std::string::npos) {
      return "a temporary file was left: " + entry.path().string();
    }
  }
  const fs::path dir(f.out_dir);
  if (code == 4 && !fs::exists(dir / "summary.json")) return "";
  try {
    // The report's data holds summary.json and scene.json whole, and log.csv's columns.
    const rotorguard::record::FlightLog log = rotorguard::record::ReadFlightLog(f.out_dir);
    rotorguard::fuzz::RequireFinite(rotorguard::record::FlightReportData(log), f.scenario, "report data");
    if (fs::exists(dir / "vehicle.yaml")) (void)rotorguard::benchmarks::LoadCalibrationLog(f.out_dir);  // sensors.csv
    if (fs::exists(dir / "report.html") &&
        rotorguard::io::ReadInputFile((dir / "report.html").string()).find("</html>") == std::string::npos) {
      return "report.html is cut short";
    }
  } catch (const std::exception& e) {
    return std::string("an output cannot be read back: ") + e.what();
  }
  return "";
}

}  // namespace

int main(int argc, char** argv) {
  std::uint64_t flights = 20, seed = 1, jobs = 1;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    std::uint64_t* v = flag == "--flights" ? &flights : flag == "--seed" ? &seed : flag == "--jobs" ? &jobs : nullptr;
    char* end = nullptr;
    if (v == nullptr || (*v = std::strtoull(argv[i + 1], &end, 10), *end != '\0') ||
        (v == &jobs && (jobs < 1 || jobs > 64))) {
      std::fputs(kUsage, stderr);
      return 2;
    }
  }
  if (argc % 2 == 0) {
    std::fputs(kUsage, stderr);
    return 2;
  }
  const fs::path scratch(rotorguard::fuzz::ScratchFolder());
  std::vector<std::string> bases;
  for (const auto& e : fs::directory_iterator(scratch / "scenarios")) bases.push_back(e.path().filename().string());
  std::sort(bases.begin(), bases.end());
  const std::vector<Key> keys = DeclaredKeys();

  Generator g(seed);
  std::map<std::string, int> refused_by_key, outcomes;
  std::vector<Flight> running;
  int findings = 0, generated = 0, flown = 0;
  double worst_ratio = 0.0;
  std::string worst;
  const auto wall_start = std::chrono::steady_clock::now();
  auto last_progress = wall_start;

  const auto finding = [&](const Flight& f, const std::string& what) {
    ++findings;
    const std::string keep = "flight-finding-" + std::to_string(seed) + "-" + std::to_string(f.index) + ".yaml";
    fs::copy_file(f.scenario, keep, fs::copy_options::overwrite_existing);
    std::fprintf(stderr, "FINDING (flight %d from %s, kept as %s): %s\n", f.index, f.base.c_str(), keep.c_str(),
                 what.c_str());
  };

  while (static_cast<std::uint64_t>(flown) < flights || !running.empty()) {
    // Fill the free slots with valid scenarios.
    while (running.size() < jobs && static_cast<std::uint64_t>(flown) < flights) {
      if (static_cast<std::uint64_t>(generated - flown) > 10 * flights + 100) {
        std::fprintf(stderr, "rotorguard_flight_fuzz: validate refused %d of %d scenarios; the generator is broken\n",
                     generated - flown, generated);
        return 1;
      }
      Flight f = DrawFlight(generated++, bases, keys, scratch, &g);
      try {
        rotorguard::benchmarks::ValidateConfigFile(f.scenario);
      } catch (const rotorguard::io::ConfigError& e) {
        ++refused_by_key[e.key_path().empty() ? e.message() : e.key_path()];
        fs::remove(f.scenario);
        continue;
      } catch (const std::exception& e) {
        finding(f, std::string("validate threw an undocumented error: ") + e.what());
        continue;
      }
      ++flown;
      f.out_dir = (scratch / ("out-" + std::to_string(f.index))).string();
      Launch(&f);
      running.push_back(f);
    }
    // Reap and check the finished ones; stop those past their budget.
    for (auto it = running.begin(); it != running.end();) {
      int status = 0;
      const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - it->start).count();
      const pid_t done = waitpid(it->pid, &status, WNOHANG);
      if (done == 0) {
        if (elapsed > kBudgetPerSimulatedSecond * it->duration_s) {
          kill(it->pid, SIGKILL);
          waitpid(it->pid, &status, 0);
          finding(*it, "ran past " + std::to_string(kBudgetPerSimulatedSecond) + " x its " +
                           std::to_string(it->duration_s) + " s simulated");
        } else {
          ++it;
          continue;
        }
      } else if (WIFSIGNALED(status)) {
        finding(*it, std::string("died of signal ") + strsignal(WTERMSIG(status)));
      } else {
        const int code = WEXITSTATUS(status);
        ++outcomes["exit " + std::to_string(code)];
        if (const std::string wrong = CheckOutputs(*it, code); !wrong.empty()) finding(*it, wrong);
        if (elapsed / it->duration_s > worst_ratio) {
          worst_ratio = elapsed / it->duration_s;
          worst = it->base;
        }
      }
      std::error_code ec;
      fs::remove_all(it->out_dir, ec);
      fs::remove(it->scenario, ec);
      it = running.erase(it);
    }
    const auto now = std::chrono::steady_clock::now();
    if (now - last_progress > std::chrono::seconds(30)) {
      std::fprintf(stderr, "%d of %llu flights\n", flown - static_cast<int>(running.size()),
                   static_cast<unsigned long long>(flights));
      last_progress = now;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }

  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  std::printf("%d scenarios generated, %d refused by validate, %d flown in %.0f s:", generated, generated - flown,
              flown, wall);
  for (const auto& [what, n] : outcomes) std::printf(" %s: %d;", what.c_str(), n);
  std::printf(" slowest %.1f s per simulated s (%s); %d finding(s)\n", worst_ratio, worst.c_str(), findings);
  std::vector<std::pair<int, std::string>> reasons;
  for (const auto& [key, n] : refused_by_key) reasons.emplace_back(n, key);
  std::sort(reasons.rbegin(), reasons.rend());
  for (std::size_t i = 0; i < std::min<std::size_t>(5, reasons.size()); ++i) {
    std::printf("  refused %d times: %s\n", reasons[i].first, reasons[i].second.c_str());
  }
  return findings == 0 ? 0 : 1;
}

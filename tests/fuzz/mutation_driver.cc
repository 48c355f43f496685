// rotorguard_fuzz TARGET: a deterministic mutation fuzzer for the targets of fuzz_targets.h, for
// builds without libFuzzer (GCC: `make test` runs it briefly on every target). It runs every seed,
// which must be accepted (else the target tests nothing), then mutants of the seeds: bit and byte
// flips, inserted, deleted and repeated spans, splices of two seeds, and tokens that break parsers
// (nan, 1e999, 2^64, YAML anchors and tags, quotes, brackets, line ends) put in place of a number
// or a span. It has no coverage feedback; the coverage-guided runs use libFuzzer
// (libfuzzer_entry.cc, `make fuzz`). A finding aborts the target; this driver then saves the
// input to crash-TARGET (timeout-TARGET for an input that ran past --timeout) and exits non-zero.
#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iterator>
#include <random>
#include <string>
#include <string_view>
#include <vector>

#include "fuzz_targets.h"
#include "rotorguard/io/config_node.h"

namespace {

using rotorguard::fuzz::Outcome;
using rotorguard::fuzz::Target;

constexpr std::string_view kUsage =
    "usage: rotorguard_fuzz TARGET [--runs N] [--seed S] [--timeout SECONDS]\n"
    "       rotorguard_fuzz TARGET --input FILE   (runs FILE alone: a finding's crash-TARGET)\n"
    "       rotorguard_fuzz --list\n";

// Tokens that parsers of YAML, JSON and CSV must refuse or handle.
constexpr std::string_view kTokens[] = {"nan",
                                        "-nan",
                                        "inf",
                                        "-inf",
                                        ".inf",
                                        ".nan",
                                        "1e999",
                                        "-1e999",
                                        "1e308",
                                        "4.9e-324",
                                        "-0",
                                        "0",
                                        "-1",
                                        "2147483648",
                                        "4294967296",
                                        "18446744073709551616",
                                        "9223372036854775807",
                                        "0x10",
                                        "1_000",
                                        "1e",
                                        "~",
                                        "null",
                                        "true",
                                        "[]",
                                        "{}",
                                        "[",
                                        "]",
                                        "{",
                                        "}",
                                        "\"",
                                        "'",
                                        ",",
                                        ":",
                                        ": ",
                                        "- ",
                                        "#",
                                        "&a ",
                                        "*a",
                                        "!!binary ",
                                        "!!str ",
                                        "<<: *a",
                                        "? ",
                                        "|",
                                        ">",
                                        "---\n",
                                        "...\n",
                                        "\n",
                                        "\r\n",
                                        "\t",
                                        " ",
                                        std::string_view("\0", 1),
                                        "\xff\xfe",
                                        "\xc3\x28",
                                        "\\u0000",
                                        "\\ud800",
                                        "imu",
                                        "esc",
                                        "odom",
                                        "cmd",
                                        "t",
                                        "status",
                                        "trial"};

// The input being run, for the signal handlers.
std::string g_current;
std::string g_crash_path, g_timeout_path;

void SaveAndDie(const std::string& path, const char* what, int sig) {
  const int fd = open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd >= 0) {
    const ssize_t ignored = write(fd, g_current.data(), g_current.size());
    (void)ignored;
    close(fd);
  }
  const ssize_t ignored = write(STDERR_FILENO, what, std::strlen(what));
  (void)ignored;
  const ssize_t ignored2 = write(STDERR_FILENO, path.c_str(), path.size());
  (void)ignored2;
  const ssize_t ignored3 = write(STDERR_FILENO, "\n", 1);
  (void)ignored3;
  signal(sig, SIG_DFL);
  raise(sig);
}

void OnCrash(int sig) { SaveAndDie(g_crash_path, "rotorguard_fuzz: the input is saved to ", sig); }
void OnTimeout(int sig) { SaveAndDie(g_timeout_path, "rotorguard_fuzz: an input ran past --timeout; saved to ", sig); }

class Mutator {
 public:
  Mutator(std::uint64_t seed, const std::vector<std::string>* seeds) : rng_(seed), seeds_(seeds) {}

  std::string Next() {
    std::string s = (*seeds_)[Below(seeds_->size())];
    const int count = 1 << Below(4);  // 1, 2, 4 or 8 mutations: small steps and big jumps
    for (int i = 0; i < count; ++i) Mutate(&s);
    return s;
  }

 private:
  std::size_t Below(std::size_t n) { return n == 0 ? 0 : std::uniform_int_distribution<std::size_t>(0, n - 1)(rng_); }
  std::string_view Token() { return kTokens[Below(std::size(kTokens))]; }

  void Mutate(std::string* s) {
    const std::size_t n = s->size();
    switch (Below(9)) {
      case 0:  // flip a bit
        if (n > 0) (*s)[Below(n)] ^= static_cast<char>(1 << Below(8));
        break;
      case 1:  // a random byte
        if (n > 0) (*s)[Below(n)] = static_cast<char>(Below(256));
        break;
      case 2: {  // insert random bytes
        std::string bytes(1 + Below(8), '\0');
        for (char& c : bytes) c = static_cast<char>(Below(256));
        s->insert(Below(n + 1), bytes);
        break;
      }
      case 3:  // erase a span
        if (n > 0) {
          const std::size_t at = Below(n);
          s->erase(at, 1 + Below(std::min<std::size_t>(n - at, 64)));
        }
        break;
      case 4:  // repeat a span
        if (n > 0) {
          const std::size_t at = Below(n);
          const std::string span = s->substr(at, 1 + Below(std::min<std::size_t>(n - at, 64)));
          s->insert(Below(n + 1), span);
        }
        break;
      case 5:  // a token somewhere
        s->insert(Below(n + 1), Token());
        break;
      case 6: {  // a token in place of a number: the values that ranges and parsers must refuse
        if (n == 0) break;
        std::size_t at = Below(n);
        while (at < n && !std::isdigit(static_cast<unsigned char>((*s)[at]))) ++at;
        std::size_t end = at;
        while (end < n &&
               (std::isdigit(static_cast<unsigned char>((*s)[end])) || (*s)[end] == '.' || (*s)[end] == 'e')) {
          ++end;
        }
        if (at < n) s->replace(at, end - at, Token());
        break;
      }
      case 7: {  // splice: this input's head, another seed's tail
        const std::string& other = (*seeds_)[Below(seeds_->size())];
        *s = s->substr(0, Below(n + 1)) + other.substr(Below(other.size() + 1));
        break;
      }
      default:  // cut the end: a file written in part
        s->resize(Below(n + 1));
        break;
    }
  }

  std::mt19937_64 rng_;
  const std::vector<std::string>* seeds_;
};

// A seed or an --input file; the program stops (exit 2) when it cannot be read.
std::string ReadInput(const std::string& path) {
  try {
    return rotorguard::io::ReadInputFile(path);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rotorguard_fuzz: %s\n", e.what());
    std::exit(2);
  }
}

bool ParseCount(const char* text, std::uint64_t* out) {
  char* end = nullptr;
  errno = 0;
  const unsigned long long v = std::strtoull(text, &end, 10);
  if (errno != 0 || end == text || *end != '\0' || text[0] == '-') return false;
  *out = v;
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  if (args.size() == 1 && args[0] == "--list") {
    for (const Target& t : rotorguard::fuzz::Targets())
      std::printf("%-14s %s\n", std::string(t.name).c_str(), std::string(t.what).c_str());
    return 0;
  }
  if (args.empty()) {
    std::fputs(kUsage.data(), stderr);
    return 2;
  }
  const Target* target = rotorguard::fuzz::FindTarget(args[0]);
  if (target == nullptr) {
    std::fprintf(stderr, "rotorguard_fuzz: no target '%s'; --list shows them\n", args[0].c_str());
    return 2;
  }
  if (args.size() == 3 && args[1] == "--input") {
    const Outcome outcome = rotorguard::fuzz::RunOne(*target, ReadInput(args[2]));
    std::printf("%s: %s\n", args[2].c_str(), outcome == Outcome::kAccepted ? "accepted" : "refused");
    return 0;
  }
  std::uint64_t runs = 10000, seed = 1, timeout_s = 10;
  for (std::size_t i = 1; i < args.size(); i += 2) {
    std::uint64_t* value = args[i] == "--runs"      ? &runs
                           : args[i] == "--seed"    ? &seed
                           : args[i] == "--timeout" ? &timeout_s
                                                    : nullptr;
    if (value == nullptr || i + 1 >= args.size() || !ParseCount(args[i + 1].c_str(), value) ||
        (value == &timeout_s && (timeout_s == 0 || timeout_s > 3600))) {
      std::fprintf(
          stderr,
          "rotorguard_fuzz: '%s' is not valid here; expected --runs N, --seed S or --timeout SECONDS in [1, 3600]\n%s",
          args[i].c_str(), kUsage.data());
      return 2;
    }
  }

  g_crash_path = "crash-" + std::string(target->name);
  g_timeout_path = "timeout-" + std::string(target->name);
  for (int sig : {SIGABRT, SIGSEGV, SIGBUS, SIGFPE, SIGILL}) signal(sig, OnCrash);
  signal(SIGALRM, OnTimeout);

  const std::vector<std::string> seed_files = rotorguard::fuzz::SeedFiles(*target);
  std::vector<std::string> seeds;
  for (const std::string& path : seed_files) seeds.push_back(ReadInput(path));
  if (seeds.empty()) {
    std::fprintf(stderr, "rotorguard_fuzz: the target %s has no seed\n", args[0].c_str());
    return 2;
  }
  const auto run = [&](std::string input) {
    g_current = std::move(input);
    alarm(static_cast<unsigned>(timeout_s));
    const Outcome outcome = rotorguard::fuzz::RunOne(*target, g_current);
    alarm(0);
    return outcome;
  };
  for (std::size_t i = 0; i < seeds.size(); ++i) {
    if (run(seeds[i]) != Outcome::kAccepted) {
      std::fprintf(stderr, "rotorguard_fuzz: the seed %s of %s is refused: its mutants would test nothing\n",
                   seed_files[i].c_str(), args[0].c_str());
      return 1;
    }
  }

  const auto start = std::chrono::steady_clock::now();
  auto last_report = start;
  Mutator mutator(seed, &seeds);
  std::uint64_t accepted = 0;
  for (std::uint64_t i = 0; i < runs; ++i) {
    if (run(mutator.Next()) == Outcome::kAccepted) ++accepted;
    const auto now = std::chrono::steady_clock::now();
    if (now - last_report > std::chrono::seconds(10)) {
      std::fprintf(stderr, "%s: %llu of %llu inputs\n", args[0].c_str(), static_cast<unsigned long long>(i + 1),
                   static_cast<unsigned long long>(runs));
      last_report = now;
    }
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("%s: %zu seeds accepted; %llu mutants in %.1f s (%.0f/s): %llu accepted, %llu refused, no finding\n",
              args[0].c_str(), seeds.size(), static_cast<unsigned long long>(runs), seconds,
              runs / std::max(seconds, 1e-9), static_cast<unsigned long long>(accepted),
              static_cast<unsigned long long>(runs - accepted));
  return 0;
}

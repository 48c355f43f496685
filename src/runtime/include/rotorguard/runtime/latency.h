#pragma once
/// What a loop of the onboard runtime reports about its timing (docs/runtime.md): a histogram of
/// latencies with logarithmic bins, recorded without allocating (the control thread records into
/// it).
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

#include "rotorguard/core/types.h"

namespace rotorguard::runtime {

/// Latencies from 100 ns to 10 s in bins a fixed ratio apart (1.8 % wide: 128 bins per decade over
/// 8 decades); below and above go to the end bins and are counted as such. Percentiles are
/// interpolated within their bin, so they are exact to 1.8 %; min, max and mean are exact.
class LatencyHistogram {
 public:
  static constexpr int kBinsPerDecade = 128;
  static constexpr int kDecades = 8;
  static constexpr TimeNs kLowestNs = 100;  // the first bin's lower edge

  void Record(TimeNs latency_ns) noexcept;
  std::uint64_t count() const { return count_; }
  /// The q-quantile, q in [0, 1], in seconds; 0 when empty.
  double Quantile(double q) const;
  double min_s() const { return count_ ? ToSeconds(min_ns_) : 0.0; }
  double max_s() const { return count_ ? ToSeconds(max_ns_) : 0.0; }
  double mean_s() const { return count_ ? sum_s_ / static_cast<double>(count_) : 0.0; }
  /// Merges another histogram's records (a loop's per-thread histograms into one).
  void Merge(const LatencyHistogram& other);
  /// The lower edge of bin i [ns].
  static double BinLowerNs(int i);

 private:
  static constexpr int kBins = kBinsPerDecade * kDecades;
  static int Bin(TimeNs ns);
  std::array<std::uint64_t, kBins> bins_{};
  std::uint64_t count_ = 0;
  TimeNs min_ns_ = 0, max_ns_ = 0;
  double sum_s_ = 0.0;
};

/// The slowest few records with the instants they belong to: where in a flight a loop was late,
/// to lay beside what else ran then. Fixed storage, so the control thread records into it too.
class SlowestRecords {
 public:
  static constexpr std::size_t kKept = 8;
  struct Record {
    TimeNs t_ns = 0;        ///< the instant (a cycle's sample, a frame's end, a step's start)
    TimeNs latency_ns = 0;  ///< what was slow about it
    TimeNs compute_ns = 0;  ///< the work itself in it, where the loop measures it (else 0)
    /// Of the latency, the part before the loop had its input, where the loop knows it (else 0):
    /// the control loop's IMU sample from its instant to its arrival at the intake (the sensor's
    /// and the transport's share; the rest less the compute is the wait for the loop's thread).
    TimeNs inbound_ns = 0;
  };
  void Add(TimeNs t_ns, TimeNs latency_ns, TimeNs compute_ns = 0, TimeNs inbound_ns = 0) noexcept;
  /// The kept records, slowest first.
  std::size_t size() const { return size_; }
  const Record& operator[](std::size_t i) const { return records_[i]; }
  /// The slowest latency recorded, 0 when none [ns].
  TimeNs max_ns() const { return size_ ? records_[0].latency_ns : 0; }

 private:
  std::array<Record, kKept> records_{};
  std::size_t size_ = 0;
};

}  // namespace rotorguard::runtime

#include "rotorguard/runtime/latency.h"

#include <algorithm>
#include <cmath>

namespace rotorguard::runtime {

double LatencyHistogram::BinLowerNs(int i) {
  return static_cast<double>(kLowestNs) * std::pow(10.0, static_cast<double>(i) / kBinsPerDecade);
}

int LatencyHistogram::Bin(TimeNs ns) {
  if (ns <= kLowestNs) return 0;
  const double decades = std::log10(static_cast<double>(ns) / static_cast<double>(kLowestNs));
  return std::clamp(static_cast<int>(decades * kBinsPerDecade), 0, kBins - 1);
}

void LatencyHistogram::Record(TimeNs latency_ns) noexcept {
  const TimeNs ns = std::max<TimeNs>(latency_ns, 0);
  ++bins_[static_cast<std::size_t>(Bin(ns))];
  min_ns_ = count_ ? std::min(min_ns_, ns) : ns;
  max_ns_ = count_ ? std::max(max_ns_, ns) : ns;
  ++count_;
  sum_s_ += ToSeconds(ns);
}

double LatencyHistogram::Quantile(double q) const {
  if (count_ == 0) return 0.0;
  q = std::clamp(q, 0.0, 1.0);
  if (q <= 0.0) return min_s();
  if (q >= 1.0) return max_s();
  // The rank of the quantile among the sorted records, then the bin it falls in, interpolated
  // linearly in its bin between the bin's edges (clamped to the exact extremes).
  const double rank = q * static_cast<double>(count_);
  double below = 0.0;
  for (int i = 0; i < kBins; ++i) {
    const auto n = static_cast<double>(bins_[static_cast<std::size_t>(i)]);
    if (n > 0.0 && below + n >= rank) {
      const double lo = std::max(BinLowerNs(i), static_cast<double>(min_ns_));
      const double hi = std::min(BinLowerNs(i + 1), static_cast<double>(max_ns_));
      const double f = std::clamp((rank - below) / n, 0.0, 1.0);
      return 1e-9 * (lo + f * std::max(0.0, hi - lo));
    }
    below += n;
  }
  return max_s();
}

void LatencyHistogram::Merge(const LatencyHistogram& other) {
  if (other.count_ == 0) return;
  for (std::size_t i = 0; i < bins_.size(); ++i) bins_[i] += other.bins_[i];
  min_ns_ = count_ ? std::min(min_ns_, other.min_ns_) : other.min_ns_;
  max_ns_ = count_ ? std::max(max_ns_, other.max_ns_) : other.max_ns_;
  count_ += other.count_;
  sum_s_ += other.sum_s_;
}

void SlowestRecords::Add(TimeNs t_ns, TimeNs latency_ns, TimeNs compute_ns, TimeNs inbound_ns) noexcept {
  if (size_ == kKept && latency_ns <= records_[kKept - 1].latency_ns) return;
  // Insertion into the sorted few: the new record's place, the slower ones before it.
  std::size_t i = size_ < kKept ? size_++ : kKept - 1;
  for (; i > 0 && records_[i - 1].latency_ns < latency_ns; --i) records_[i] = records_[i - 1];
  records_[i] = {t_ns, latency_ns, compute_ns, inbound_ns};
}

}  // namespace rotorguard::runtime

#include "rotorguard/harness/flight_recorder.h"

#include <fmt/format.h>

#include <filesystem>
#include <stdexcept>

#include "rotorguard/core/error.h"
#include "rotorguard/record/flight_mcap.h"
#include "rotorguard/record/report.h"
#include "rotorguard/record/sensor_log.h"
#include "rotorguard/vehicle/multirotor.h"

namespace rotorguard::harness {

namespace {

namespace fs = std::filesystem;
using vehicle::StateView;

/// Fills one row of a log column by column, checking at the end that it filled them all.
class RowWriter {
 public:
  explicit RowWriter(io::NumericTable* table) : table_(table) {}
  void operator()(double v) { table_->values[c_++].push_back(v); }
  void v3(const Vector3& v) { (*this)(v.x()), (*this)(v.y()), (*this)(v.z()); }
  void q4(const Quaternion& q) { (*this)(q.w()), (*this)(q.x()), (*this)(q.y()), (*this)(q.z()); }
  ~RowWriter() { RG_INVARIANT(c_ == table_->columns.size(), "log row and LogColumns disagree"); }

 private:
  io::NumericTable* table_;
  std::size_t c_ = 0;
};

void PutReference(const ReferencePoint& r, RowWriter& put) {
  put.v3(r.p_W);
  put.v3(r.v_W);
  put(r.yaw);
}

void PutEstimate(const StateEstimate& e, RowWriter& put) {
  put.v3(e.p_W);
  put.q4(e.q_WB);
  put.v3(e.v_W);
  put.v3(e.w_B);
}

/// mi_i, pi_i, health_i of the first n rotors of `rotors` (fdd::RotorStatus or a cycle's
/// runtime::RotorHealthSample).
template <typename Rotors>
void PutFdd(const Rotors& rotors, int n, RowWriter& put) {
  const auto each = [&](auto&& value) {
    for (int i = 0; i < n; ++i) put(value(rotors[static_cast<std::size_t>(i)]));
  };
  each([](const auto& r) { return static_cast<double>(r.motor_index); });
  each([](const auto& r) { return static_cast<double>(r.propeller_index); });
  each([](const auto& r) { return static_cast<double>(static_cast<int>(r.health)); });
}

/// The newest LiDAR frame's health, held until the next frame; before the first, a default
/// summary (nothing used or matched, all zeros).
void PutLio(const perception::LioFrameSummary& f, RowWriter& put) {
  put(f.used ? 1.0 : 0.0);
  put(f.degenerate ? 1.0 : 0.0);
  put(f.points_matched);
  put(f.residual_rms_m);
  // Infinite when no point matched (record::kLioWeakestStdCapM); `!(x < cap)` also caps a NaN.
  put(f.weakest_std_m < record::kLioWeakestStdCapM ? f.weakest_std_m : record::kLioWeakestStdCapM);
}

/// One row of log.csv (record/flight_log.h, LogColumns): the truth, the stack's reference,
/// estimate and outputs, the rotors, and the FDD indices, NMPC solve time and LiDAR-inertial
/// odometry's health when the stack has them.
void AppendRow(const sim::Simulator& sim, const StackRow& row, io::NumericTable* table) {
  const StateView s(sim.state());
  RowWriter put(table);
  put(sim.time_s());
  put.v3(s.p_W());
  put.q4(s.q_WB());
  put.v3(s.v_W());
  put.v3(s.w_B());
  PutReference(row.reference, put);
  PutEstimate(row.estimate, put);
  put.v3(sim.wind());
  put(sim.landed() ? 1.0 : 0.0);
  put(static_cast<int>(row.mode));
  const int n = sim.model().num_rotors();
  for (int i = 0; i < n; ++i) put(sim.applied_command()[i]);
  for (int i = 0; i < n; ++i) put(sim.rotor_thrusts()[i]);
  for (int i = 0; i < n; ++i) put(vehicle::RadPerSecondToRpm(sim.motor_speeds()[i]));
  for (int i = 0; i < n; ++i) put(static_cast<int>(sim.faults()[i].kind));  // docs/scenarios.md, "Outputs"
  if (!row.stack) return;
  const stack::FlightStack& st = *row.stack;
  if (const fdd::FaultDetector* detector = st.fault_detector()) PutFdd(detector->rotors(), n, put);
  if (const control::NmpcController* nmpc = st.nmpc()) put(1e3 * nmpc->summary().solve_time_s);
  if (const stack::LioEstimator* lio = st.lio()) {
    const std::vector<perception::LioFrameSummary>& frames = lio->frames();
    PutLio(frames.empty() ? perception::LioFrameSummary{} : frames.back(), put);
  }
}

std::string InFolder(const std::string& dir, const char* name) { return (fs::path(dir) / name).string(); }

}  // namespace

void AppendCycleRow(const runtime::CycleTelemetry& c, const perception::LioFrameSummary* lio_frame,
                    io::NumericTable* table) {
  RowWriter put(table);
  put(ToSeconds(c.command.state_t_ns));
  PutReference(c.reference, put);
  PutEstimate(c.estimate, put);
  put(static_cast<int>(c.mode));
  const auto n = static_cast<int>(c.command.thrust_n.size());
  for (int i = 0; i < n; ++i) put(c.command.thrust_n[i]);
  if (c.fdd_rotors > 0) PutFdd(c.health, c.fdd_rotors, put);
  if (lio_frame) PutLio(*lio_frame, put);
}

void PrepareRunFolder(const std::string& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw std::runtime_error(fmt::format("cannot create {}: {}", dir, ec.message()));
  for (const char* name : kRunFolderFiles) fs::remove(InFolder(dir, name), ec);
}

FlightRecorder::FlightRecorder(const FlightRecorderOptions& options, const Scenario& scenario)
    : options_(options),
      scenario_(&scenario),
      log_period_ns_(PeriodFromRate(scenario.log_rate_hz)),
      scene_(scenario.vehicle, scenario.world, {}, scenario.assembly.get()) {
  if (!writes()) return;
  PrepareRunFolder(options_.out_dir);
  if (options_.log_format != LogFormat::kMcap) {
    sensors_.emplace(InFolder(options_.out_dir, "sensors.csv"));
    sensor_buffer_ = record::kSensorLogHeader;
  }
}

void FlightRecorder::Begin(const stack::FlightStack& st, int num_rotors) {
  flight_.table.columns =
      record::LogColumns({.rotors = num_rotors,
                          .fdd = st.fault_detector() != nullptr,
                          .nmpc = st.nmpc() != nullptr,
                          .lio = st.lio() != nullptr});
  flight_.table.values.resize(flight_.table.columns.size());
}

void FlightRecorder::BeginWithoutStack(int num_rotors) {
  flight_.table.columns = record::LogColumns({.rotors = num_rotors});
  flight_.table.values.resize(flight_.table.columns.size());
}

void FlightRecorder::OnCommand(const RotorCommand& command) {
  if (sensors_) record::AppendCommand(command, &sensor_buffer_);
}

void FlightRecorder::OnControlCycle(TimeNs t, const stack::FlightStack& st, const RotorCommand& command) {
  if (!writes()) return;
  if (sensors_) record::AppendCommand(command, &sensor_buffer_);
  scene_.OnControlCycle(ToSeconds(t), st);
}

void FlightRecorder::OnStep(TimeNs t, const sim::Simulator& sim, const StackRow& st) {
  if (!RowDue(t)) return;
  AppendRow(sim, st, &flight_.table);
  if (writes()) scene_.OnTime(ToSeconds(t));
  next_log_ns_ += log_period_ns_;
}

void FlightRecorder::AfterStep() {
  if (sensors_ && sensor_buffer_.size() > (1u << 20)) {
    sensors_->Write(sensor_buffer_);
    sensor_buffer_.clear();
  }
}

void FlightRecorder::WriteFlight(const sim::Simulator& sim, const StackRow& st, const vehicle::VehicleParams& stack_vehicle) {
  if (!logs()) return;
  AppendRow(sim, st, &flight_.table);
  if (!writes()) return;
  flight_.scene = scene_.ToJson();
  if (options_.log_format != LogFormat::kMcap) {
    record::WriteFlightLogFiles(flight_, options_.out_dir);
    sensors_->Write(sensor_buffer_);
    sensors_->Commit();
  }
  // The vehicle the stack flew, so that the run's folder is enough to replay its sensor log.
  io::WriteFileAtomically(InFolder(options_.out_dir, "vehicle.yaml"), VehicleToYaml(stack_vehicle));
  // The vehicle the simulator flew (summary.json's "truth" has the per-rotor thrust ratios, the
  // IMU's offset and the external torque, which a vehicle file does not hold).
  io::WriteFileAtomically(InFolder(options_.out_dir, "truth_vehicle.yaml"), VehicleToYaml(sim.model().params()));
}

void FlightRecorder::WriteSummary(const RunSummary& summary) {
  if (!writes()) return;
  flight_.summary = summary.ToJson();
  if (options_.log_format != LogFormat::kCsv)
    record::WriteFlightMcap(flight_, InFolder(options_.out_dir, "flight.mcap"));
  io::WriteFileAtomically(InFolder(options_.out_dir, "summary.json"), flight_.summary.dump(2) + "\n");
  if (options_.report) record::WriteFlightReport(flight_, InFolder(options_.out_dir, "report.html"));
}

}  // namespace rotorguard::harness

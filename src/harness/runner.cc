#include "rotorguard/harness/runner.h"

#include "rotorguard/harness/flight.h"
#include "rotorguard/record/sensor_log.h"
#include "rotorguard/sim/simulator.h"
#include "rotorguard/stack/flight_stack.h"

namespace rotorguard::harness {

void AppendSensorLog(const sim::SensorOutputs& o, std::string* sensor_log) {
  if (!sensor_log) return;
  if (o.imu) record::AppendImu(*o.imu, sensor_log);
  if (o.esc) record::AppendEsc(*o.esc, sensor_log);
  if (o.odometry) record::AppendOdometry(*o.odometry, sensor_log);
  // The LiDAR is not in sensors.csv: 200k points/s would swamp it.
}

void DeliverToStack(const sim::SensorOutputs& o, stack::FlightStack* st, std::string* sensor_log) {
  if (o.imu) st->OnImu(*o.imu);
  if (o.esc) st->OnEscTelemetry(*o.esc);
  if (o.odometry) st->OnOdometry(*o.odometry);
  if (o.lidar) st->OnLidar(*o.lidar);
  if (o.battery) st->OnBattery(*o.battery);
  AppendSensorLog(o, sensor_log);
}

RunSummary RunScenario(const Scenario& sc, const RunOptions& options) {
  Flight flight(sc, options);
  flight.Fly();
  return flight.Finish();
}

}  // namespace rotorguard::harness

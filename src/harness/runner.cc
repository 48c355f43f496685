#include "rotorguard/harness/runner.h"

#include "rotorguard/harness/flight.h"
#include "rotorguard/record/sensor_log.h"
#include "rotorguard/sim/simulator.h"
#include "rotorguard/stack/flight_stack.h"

namespace rotorguard::harness {

void DeliverToStack(const sim::SensorOutputs& o, stack::FlightStack* st, std::string* sensor_log) {
  if (o.imu) {
    st->OnImu(*o.imu);
    if (sensor_log) record::AppendImu(*o.imu, sensor_log);
  }
  if (o.esc) {
    st->OnEscTelemetry(*o.esc);
    if (sensor_log) record::AppendEsc(*o.esc, sensor_log);
  }
  if (o.odometry) {
    st->OnOdometry(*o.odometry);
    if (sensor_log) record::AppendOdometry(*o.odometry, sensor_log);
  }
  if (o.lidar) st->OnLidar(*o.lidar);  // not in sensors.csv: 200k points/s would swamp it
}

RunSummary RunScenario(const Scenario& sc, const RunOptions& options) {
  Flight flight(sc, options);
  flight.Fly();
  return flight.Finish();
}

}  // namespace rotorguard::harness

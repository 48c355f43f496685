#pragma once
/// The sensor log of a run (DIR/sensors.csv): every message the flight stack received, in the
/// order it received them, and every command it sent. It is what a flight computer could record,
/// and all that an offline replay of the fault detectors needs (rotorguard fdd-calibrate).
///
/// Format (CSV, one message per line, after the header line "type,t_ns,values..."):
///   imu,T,f_x,f_y,f_z,w_x,w_y,w_z              specific force [m/s^2] and rate [rad/s], body frame
///   esc,T,w_0,...,w_{n-1}                        measured motor speeds [rad/s]
///   odom,T,p_x,p_y,p_z,q_w,q_x,q_y,q_z,v_x,v_y,v_z
///   cmd,T,u_0,...,u_{n-1}                        the stack's thrust command [N] at its cycle T
/// T is the message's time stamp [ns] (an ESC sample's is when it was measured, before transport).
/// Numbers are in their shortest exact form; nan and inf are written as such (the stack ignores a
/// non-finite message, and a replay must see it to ignore it too).
#include <string>
#include <variant>
#include <vector>

#include "rotorguard/core/messages.h"

namespace rotorguard::record {

/// One line of a sensor log: the message it holds.
using SensorRecord = std::variant<ImuSample, EscTelemetry, OdometrySample, RotorCommand>;

/// A record's time stamp [ns].
inline TimeNs RecordTime(const SensorRecord& r) {
  return std::visit([](const auto& message) { return message.t_ns; }, r);
}

inline constexpr std::string_view kSensorLogHeader = "type,t_ns,values...\n";

void AppendImu(const ImuSample& m, std::string* out);
void AppendEsc(const EscTelemetry& m, std::string* out);
void AppendOdometry(const OdometrySample& m, std::string* out);
void AppendCommand(const RotorCommand& m, std::string* out);

/// Reads a sensor log for a vehicle of `num_rotors`. Throws io::InputFileError when the file cannot
/// be read or is malformed (truncated, something that is not a number, a wrong field count, time
/// going backwards per message type); the reason names the line and its byte offset.
std::vector<SensorRecord> ReadSensorLog(const std::string& path, int num_rotors);

}  // namespace rotorguard::record

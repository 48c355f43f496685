#pragma once
/// A flight as an MCAP file (io/mcap.h) that Foxglove and PlotJuggler open: JSON messages with
/// Foxglove schema names, and the whole record for rotorguard's own tools (docs/report.md, "MCAP"):
///   /tf             foxglove.FrameTransform   world -> base_link (the true pose), log rate
///   /pose           foxglove.PoseInFrame      the true pose
///   /estimate       foxglove.PoseInFrame      the stack's estimate
///   /reference      foxglove.PoseInFrame      the reference position and heading
///   /rotors         rotorguard.RotorState     per rotor: command and thrust [N], rpm, injected fault
///   /fdd            rotorguard.FddIndices     per rotor: M_i, P_i and diagnosed health (with FDD)
///   /obstacles      foxglove.SceneUpdate      boxes and trees at t = 0, moving boxes as they move
///   /planner/trajectory foxglove.SceneUpdate  each plan the navigator adopted, as a line strip
///   /map            foxglove.PointCloud       occupied voxel centres of the LiDAR map (2 Hz)
///   /rotorguard/log rotorguard.LogRow         every column of log.csv, exactly
/// and a metadata record "rotorguard" with summary.json, scene.json and the log's column names.
#include <string>

#include "rotorguard/record/flight_log.h"

namespace rotorguard::record {

/// Writes the flight to `path` atomically.
void WriteFlightMcap(const FlightLog& log, const std::string& path);

/// Reads a flight back from its MCAP file: io::CorruptFileError (with the byte offset) when the
/// file is damaged or lacks the rotorguard record, io::InputFileError when it cannot be read.
FlightLog ReadFlightMcap(const std::string& path);

}  // namespace rotorguard::record

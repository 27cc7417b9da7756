// The inertia CSV (header row, columns by name; unknown columns ignored):
//   t                        s, strictly increasing
//   px,py,pz                 object position in the world (m)
//   qw,qx,qy,qz              quaternion rotating object-frame vectors into the
//                            world (normalised here; rejected if its norm < 1e-3)
// and ONE force source:
//   fx,fy,fz,tx,ty,tz        wrench applied to the object (object frame,
//                            torque about the object origin); optional
//                            per-sample sigmas f_sigma (N), t_sigma (N m)
//   c{i}_px,c{i}_py,c{i}_pz, c{i}_fx,c{i}_fy,c{i}_fz   for i = 0..n-1:
//                            contact point and force applied to the object
//                            (object frame); zero force = broken contact;
//                            optional per-sample sigma c{i}_sigma (N)
// and optional measured kinematics (all of w, dw, a; v optional):
//   wx,wy,wz (object frame), vx,vy,vz (world), dwx,dwy,dwz (object frame),
//   ax,ay,az (world, without gravity).
#pragma once

#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "tactforce/io/csv.h"
#include "tactforce/inertia/types.h"

namespace tactforce::inertia {

// Converts a parsed table. Errors are InvalidArgument naming the source,
// line and column: "run.csv: missing column(s) qz", "run.csv:12: column 't':
// time 0.11 is not after the previous sample's 0.11", "run.csv:7: columns
// qw,qx,qy,qz: quaternion norm 2e-09 is near zero", "run.csv: contact 1:
// missing column(s) c1_fz", "run.csv: 3 samples, at least 4 needed ...".
absl::StatusOr<InertiaSamples> InertiaSamplesFromCsv(const io::CsvTable& table);

// io::ReadCsvFile + InertiaSamplesFromCsv.
absl::StatusOr<InertiaSamples> ReadInertiaCsvFile(const std::string& path);
absl::StatusOr<InertiaSamples> ParseInertiaCsv(const std::string& text, const std::string& source);

// Checks samples built in code (e.g. from RPC messages): errors name
// "samples[12].orientation", "samples[3].contacts[1].force", ... or, when
// line_numbers are set, "<source>:<line>: column ...". Quaternions must be
// non-zero (norm >= 1e-3); they need not be unit.
absl::Status ValidateInertiaSamples(const InertiaSamples& samples);

// Normalises every quaternion (after validation).
void NormalizeOrientations(InertiaSamples& samples);

// Writes the CSV format above (%.17g), kinematics columns when present.
std::string InertiaSamplesToCsv(const InertiaSamples& samples);
absl::Status WriteInertiaCsvFile(const InertiaSamples& samples, const std::string& path);

}  // namespace tactforce::inertia

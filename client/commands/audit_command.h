// `tactforce audit`: what the sensor model gets wrong on measured data,
// through the Backend (Audit.AuditModel; in this process unless --server).
#pragma once

#include <string>

#include "CLI/CLI.hpp"
#include "backend.h"
#include "cli_common.h"

namespace tactforce::cli {

struct AuditArgs {
  std::string csv;  // t,reference,reading[,shear][,trial] or per taxel t,reference,taxel_0..
  std::string reference_path;  // two-stream mode: t,value[,shear]
  std::string reading_path;    //                  t,value
  // Two streams: the clock offset (reading clock minus reference clock) is
  // estimated by default (cross-correlation within +/- max_clock_offset, then
  // refined by the audit; 'delay' is then not a candidate: a constant sensor
  // delay is indistinguishable from a clock offset). --clock-offset S fixes it
  // (and 'delay' is audited); --no-clock-offset fixes it at 0.
  double clock_offset = 0.0;  // s, with clock_offset_given
  bool clock_offset_given = false;
  bool no_clock_offset = false;
  double max_clock_offset = 1.0;     // s, half-width of the estimation search
  double clock_offset_centre = 0.0;  // s, centre of the estimation search
  std::string model_path;            // a given model JSON instead of the affine nominal
  std::string out_dir;
  bool force = false;  // replace an earlier report's files in out_dir
  std::string units = "reading units";
  double heldout_fraction = 0.35;
  int max_causes = 3;
  int taxels = 0;  // per-taxel CSV: expected taxel_<j> columns (0 = as found)
  int blocks = 4;  // blocked hold-out: contiguous blocks (0 = off)
  bool quiet = false;
  OutputFormat output;  // table: the summary; json: report.json
  BackendArgs backend;  // --local | --server ADDR, TLS, --deadline-ms
};
CLI::App* AddAuditCommand(CLI::App& app, AuditArgs& args);
int RunAuditCommand(const AuditArgs& args);

}  // namespace tactforce::cli

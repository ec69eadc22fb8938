// Run data in and out: the CSV contract of docs/file-formats.md, MATLAB files through
// matio, the column mapping and IMU mounting of run.yaml, angle unwrapping, and
// the validation of what was read.
#pragma once

#include <string>

#include "core/io/file_util.h"
#include "core/model/run_data.h"
#include "core/model/run_description.h"

namespace triadcal {

// Loads the data file named by run.data_path (format from the extension: .csv,
// .txt -> CSV contract / whitespace text with the same header rules; .mat ->
// MATLAB via matio), applies the column mapping, units, mounting and unwrapping,
// validates, and returns the run. Non-fatal findings go to *warnings (one line
// each, with counts). Throws InputError("FILE:LINE: what is wrong") on bad input.
// The gyro columns gx gy gz (SPEC section 10) are read when run.gyro is set
// (all three required; RunData::gyro_rad_s in rad/s, platform frame) and
// otherwise left alone, with a warning when the file has them.
// threads: 1 reads on the calling thread alone (TextTableOptions::threads).
RunData LoadRunData(const RunDescription& run, RunWarnings* warnings, int threads = 0);

// Writes the CSV contract: t, lambda1, lambda2 [deg], wx, wy, wz [mV], and
// lambda1_rate, lambda2_rate [deg/s] / temp_C / gx, gy, gz [deg/s] when
// present (in that order), with shortest
// round-trip formatting (no precision lost). Writes to a temporary file and
// renames it, so a failure leaves no partial file (WriteFileAtomically, with
// `options`).
void WriteRunCsv(const RunData& run, const std::string& path, const std::string& comment,
                 const WriteOptions& options = {});

}  // namespace triadcal

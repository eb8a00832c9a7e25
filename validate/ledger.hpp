// Calibration output: the model with an effect added (YAML), and the model ledger (SQLite): every
// model version with its parent, the effect that made it and its fit per channel on the record,
// plus a plot of the error falling version by version.
#pragma once

#include <map>
#include <string>

#include "validate/diagnose.hpp"

namespace ff {

// The model document with the effect's switches and fitted values set, as YAML text, headed by a
// comment naming the source model, the record, the effect and its fitted values.
std::string format_calibrated_model(const ModelSource& src, const EffectFit& fit, const std::string& record_path);

// Adds `before` (if the ledger does not know its file yet) and `after` (child of before) to the
// ledger at `ledger_path`, with each one's fit % and RMSE per channel on the record (calc_record_fits,
// an arm's calc_arm_record_fits), and redraws
// ledger_path + ".png": the error (100 - fit %) per channel against version, of the versions fitted
// to this record in this mode. Returns those versions as a text table.
std::string record_calibration(const std::string& ledger_path, const std::string& before_path,
                               const std::map<std::string, Fit>& before, const std::string& after_path,
                               const std::map<std::string, Fit>& after, const EffectFit& fit, const Record& r,
                               ReplayMode mode);

// A rig model's fit per scored channel on a record (what the ledger keeps of a version).
std::map<std::string, Fit> calc_record_fits(const Model& m, const Record& r, ReplayMode mode);

// The ledger's part of that: the versions at `ledger_path` fitted to the record `record` in `mode`, as the
// text table, and the plot ledger_path + ".png". A file that is no ledger (another schema, a damaged
// database) throws std::runtime_error naming it.
std::string report_ledger(const std::string& ledger_path, const std::string& record, ReplayMode mode);

}  // namespace ff

// Comparing an arm model with an arm measurement record (docs/cli.md, `flexfarm compare` on an arm
// model): the model follows the record's references (free run, arm_record.hpp replay_arm_record), and
// every channel both have is scored as the rig's compare scores its channels (compare.hpp): fit %,
// RMSE and the residual's analysis (residuals.hpp). There is no k-step prediction yet (it needs an
// observer on the arm's tree).
#pragma once

#include <string>
#include <vector>

#include "arm/arm_model.hpp"
#include "validate/compare.hpp"  // ChannelCompare
#include "validate/record.hpp"
#include "validate/residuals.hpp"

namespace ff {

struct ArmCompareResult {
  std::string record_source;
  double control_period = 0.0;          // s, the model's controller sample time
  bool resampled = false;               // the record's times are not the controller's samples
  bool ok = true;                       // the replay's lane status
  std::vector<double> t;                // s, the record's times
  // Scored: each <joint>.angle, <joint>.torque, then tool.x/y/z and the deflections the record has,
  // but none constant over the record (no fit to score: listed in `constant`). Per channel only the
  // free-run members (measured, free_run, fit_free, free_analysis) are set.
  std::vector<ChannelCompare> channels;
  std::vector<std::string> inputs;      // per channel the record column its residual is correlated with:
                                        // the joint's .ref (the first joint's for the tool and the links)
  std::vector<std::vector<double>> refs;  // per channel that column (for the overlay of a joint's angle)
  std::vector<std::string> constant;    // channels present in both but constant in the record
  ResidualOptions options;
};

// Replays the record (checked by check_arm_record) on the model and scores every channel. The states
// a channel's residual is binned against: its joint's velocity (<joint>.rate, else central differences
// of <joint>.angle), angle and torque (when recorded); every joint's velocity and angle for the tool and
// the links. A failed replay is a result: its fits are -inf, its analyses invalid.
ArmCompareResult compare_arm_record(const ArmModel& m, const Record& r, const ResidualOptions& options = {});

// The fit table (markdown) printed by `flexfarm compare`: channel, unit, fit %, RMSE.
std::string format_arm_fit_table(const ArmCompareResult& r);
// report.md: the replay in words, the fit table, per channel the failure summary, the plots.
std::string format_arm_compare_report(const ArmCompareResult& r);
// compare.json (docs/formats.md, "compare.json", the arm form).
std::string format_arm_compare_json(const ArmCompareResult& r);
// Writes DIR/report.md, DIR/compare.json and per channel overlay_CH.png (measured, model; a joint's
// angle with its reference), residual_CH.png, acf_CH.png, ccf_CH.png, spectrum_CH.png (CH the channel
// name with '.' as '_'), each atomically. Returns the file names written.
std::vector<std::string> write_arm_compare_report(const ArmCompareResult& r, const std::string& dir);

}  // namespace ff

// Comparing an arm model with an arm measurement record (docs/cli.md, `flexfarm compare` on an arm
// model): the model follows the record's references (free run, arm_record.hpp replay_arm_record) and,
// with k > 0, k samples ahead of an observer's estimate of its state (the k-step prediction,
// arm_observer.hpp: every k controller samples a prediction restarts from the estimate and runs k
// samples without the record's measurements); every channel both have is scored for each as the rig's
// compare scores its channels (compare.hpp): fit %, RMSE and the residual's analysis (residuals.hpp).
#pragma once

#include <string>
#include <vector>

#include "arm/arm_model.hpp"
#include "validate/arm_observer.hpp"
#include "validate/compare.hpp"  // ChannelCompare
#include "validate/record.hpp"
#include "validate/residuals.hpp"

namespace ff {

struct ArmCompareResult {
  std::string record_source;
  double control_period = 0.0;          // s, the model's controller sample time
  bool resampled = false;               // the record's times are not the controller's samples
  bool ok = true;                       // the free run's lane status
  int k_ahead = 0;                      // the k-step horizon, controller samples; 0: the free run only
  bool k_ok = false;                    // with k_ahead: the observer was designed and its lanes stayed finite
  ArmObserverDesign observer;           // with k_ahead: the observer (channels, noise, gains)
  std::vector<double> t;                // s, the record's times
  // Scored: each <joint>.angle, <joint>.torque, then tool.x/y/z and the deflections the record has,
  // but none constant over the record (no fit to score: listed in `constant`). Per channel the free
  // run's members (measured, free_run, fit_free, free_analysis) and with k_ahead the k-step's (k_step,
  // fit_k, k_analysis; without, fit_k NaN).
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
// the links. With k_ahead > 0 the k-step prediction too (run_arm_observer with `observer`). A failed
// replay or prediction is a result: its fits are -inf, its analyses invalid.
ArmCompareResult compare_arm_record(const ArmModel& m, const Record& r, const ResidualOptions& options = {},
                                    int k_ahead = 0, const ArmObserverOptions& observer = {});

// One sentence for report.md: how the k-step start state is estimated (channels, noise, gains).
std::string describe_arm_observer(const ArmCompareResult& r);
// The fit table (markdown) printed by `flexfarm compare`: channel, unit, fit %, RMSE (with k, of the
// free run and of the k-step prediction).
std::string format_arm_fit_table(const ArmCompareResult& r);
// report.md: the replay in words, the fit table, per channel the failure summary, the plots.
std::string format_arm_compare_report(const ArmCompareResult& r);
// compare.json (docs/formats.md, "compare.json", the arm form).
std::string format_arm_compare_json(const ArmCompareResult& r);
// Writes DIR/report.md, DIR/compare.json and per channel overlay_CH.png (measured, model, with k the
// k-step prediction; a joint's angle with its reference), residual_CH.png, acf_CH.png, ccf_CH.png, spectrum_CH.png (CH the channel
// name with '.' as '_'), each atomically. Returns the file names written.
std::vector<std::string> write_arm_compare_report(const ArmCompareResult& r, const std::string& dir);

}  // namespace ff

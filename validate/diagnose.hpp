// Which physical effect is the model missing? Each candidate (validate/effects.hpp) is added to the
// model and its parameters fitted to the record by nonlinear least squares (Ceres, Levenberg-
// Marquardt; the Jacobian by forward differences, its columns run as lanes of one batch). Candidates
// are ranked by the Bayesian information criterion against the base model:
//   BIC = n ln(RSS / n) + k ln n,   Delta BIC = BIC(effect) - BIC(base),
// with n residuals (every scored channel, each divided by its measured standard deviation) and k
// fitted parameters. Delta BIC < -10 is "very strong" evidence (Kass and Raftery 1995): significant,
// when the fit also visibly improves (kMinFitGain).
#pragma once

#include <yaml-cpp/yaml.h>

#include <map>
#include <string>
#include <vector>

#include "sweep/paths.hpp"
#include "validate/effects.hpp"
#include "validate/record.hpp"
#include "validate/replay.hpp"

namespace ff {

inline constexpr double kSignificantDeltaBic = -10.0;
// ... and must improve the fit of some channel by this many percentage points: on a noise-free
// record whose residual is rounding, any parameter "explains" a share of it, and BIC alone says yes.
inline constexpr double kMinFitGain = 0.02;

// The model to diagnose: its document (so effects can be set by path) and where it came from.
struct ModelSource {
  YAML::Node doc;
  std::string path;
  std::vector<Assignment> set;  // --set overrides, applied first
};
ModelSource load_model_source(const std::string& path, const std::vector<std::string>& sets);
Model build_model(const ModelSource& src, const std::vector<Assignment>& extra = {});

struct EffectFit {
  std::string effect;
  std::string physics;
  std::vector<std::pair<std::string, std::string>> switches;  // fixed settings the effect needs (path -> YAML)
  std::map<std::string, double> params;       // fitted values by path
  std::map<std::string, double> stderr_;      // their standard errors (NaN when not identifiable)
  std::vector<std::string> unidentifiable;    // fitted paths the record cannot tell apart from the others
  std::vector<std::string> refit;             // the existing parameters re-fitted with it (also in params)
  std::map<std::string, double> fit_percent;  // per scored channel
  double rss = NAN;                            // normalised residual sum of squares
  int k = 0;                                   // parameters fitted (a grid search counts one)
  double delta_bic = NAN;
  bool significant = false;
  bool ok = false;                             // false: the fit failed (reason in `note`)
  std::string note;
  std::vector<Assignment> assignments() const; // what to set in the model to add this effect
};

struct Diagnosis {
  ReplayMode mode = ReplayMode::kClosedLoop;
  std::vector<std::string> channels;
  int n = 0;                                   // residuals
  double base_rss = NAN;
  std::map<std::string, double> base_fit;      // fit % per channel of the base model (after its re-fit)
  std::map<std::string, double> base_params;   // the re-fitted existing parameters of the baseline
  std::vector<std::string> refit;              // their paths (as given, or as `auto` chose them for no effect)
  std::vector<EffectFit> ranking;              // best (lowest Delta BIC) first
  std::string verdict = "none";                // the best significant effect, or "none"
};

struct DiagnoseOptions {
  ReplayMode mode = ReplayMode::kClosedLoop;
  std::vector<std::string> only;               // effects to try (empty = all that apply)
  // Existing parameters re-fitted with the baseline and every effect (paths); {"auto"}: for each
  // effect the (at most two) existing parameters the residual is most sensitive to that the effect
  // does not fit itself; {} or {"none"}: none (the default: with `auto` by default the hidden-effect
  // acceptance of docs/validation.md fell to 68 % first, 89 % among the first three).
  std::vector<std::string> refit;
  int max_iterations = 25;
  int max_samples = 1500;                      // per channel: the record is decimated to at most this
};

Diagnosis diagnose(const ModelSource& src, const Record& r, const DiagnoseOptions& opt);

// One effect fitted alone (what `calibrate --add` uses).
EffectFit fit_effect(const ModelSource& src, const Record& r, const DiagnoseOptions& opt, const std::string& effect);

// JSON of a diagnosis (docs/formats.md, "diagnose JSON").
std::string format_diagnosis_json(const Diagnosis& d);
// A human-readable summary for the terminal.
std::string format_diagnosis_text(const Diagnosis& d);

}  // namespace ff

// truth_record KEY=VALUE ... --out FILE.csv: a measurement record of the truth rig (truth_sim.hpp).
// Every TruthRig field by its dotted name, e.g.
//   truth_record drive.enabled=true drive.backlash=0.002 sensors.tip_deflection.delay=30 seed=7 --out r.csv
// --stats prints CVODE's counters. Exit 0 on success, 2 on a bad argument (one message), 1 when the simulation fails.
#include <cstdio>
#include <exception>
#include <string>

#include "tests/validate/truth/truth_sim.hpp"
#include "validate/record.hpp"

namespace {

void usage(std::FILE* to) {
  std::fprintf(to, "usage: truth_record [KEY=VALUE ...] --out FILE.csv [--stats]\n\nfields (default values):\n");
  for (const auto& f : ff::truth::list_truth_fields(ff::truth::TruthRig{}))
    std::fprintf(to, "  %-34s %-14s %s\n", f.name.c_str(), f.unit.c_str(), f.value.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  ff::truth::TruthRig rig;
  std::string out;
  bool stats = false;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      usage(stdout);
      return 0;
    }
    if (arg == "--stats") {
      stats = true;
      continue;
    }
    if (arg == "--out") {
      if (i + 1 == argc) {
        std::fprintf(stderr, "truth_record: --out needs a file name\n");
        return 2;
      }
      out = argv[++i];
      continue;
    }
    const auto eq = arg.find('=');
    if (eq == std::string::npos || eq == 0) {
      std::fprintf(stderr, "truth_record: expected KEY=VALUE or --out FILE, got '%s' (--help lists the keys)\n",
                   arg.c_str());
      return 2;
    }
    try {
      ff::truth::set_truth_field(rig, arg.substr(0, eq), arg.substr(eq + 1));
    } catch (const std::invalid_argument& e) {
      std::fprintf(stderr, "truth_record: %s (--help lists the keys)\n", e.what());
      return 2;
    }
  }
  if (out.empty()) {
    std::fprintf(stderr, "truth_record: --out FILE.csv is required\n");
    return 2;
  }
  try {
    const ff::truth::TruthRun run = ff::truth::run_truth(rig);
    ff::write_record_csv(run.record, ff::truth::truth_record_columns(rig), out);
    if (stats)
      std::fprintf(stderr, "truth_record: %zu samples, CVODE %ld steps, %ld right-hand sides, %ld Jacobians, %ld restarts\n",
                   run.trace.t.size(), run.stats.steps, run.stats.rhs_evals, run.stats.jacobian_evals,
                   run.stats.restarts);
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "truth_record: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "truth_record: %s\n", e.what());
    return 1;
  }
  return 0;
}

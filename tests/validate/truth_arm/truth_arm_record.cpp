// truth_arm_record [--arm 2|3|6] KEY=VALUE ... --out FILE.csv: an arm measurement record of the truth arm
// (truth_arm.hpp) in flexfarm's arm-record form, e.g.
//   truth_arm_record --arm 2 j1.friction.coulomb=3 j1.sensors.angle.noise=1e-4 seed=7 --out r.csv
//   flexfarm diagnose --model tests/data/truth_arm/arm2.yaml --data r.csv --out out/d
// --arm N starts from the suite's N-joint arm (tests/data/truth_arm/armN.yaml); without it, the defaults.
// Exit 0 on success, 2 on a bad argument (one message), 1 when the simulation fails.
#include <cstdio>
#include <exception>
#include <string>

#include "tests/validate/truth_arm/truth_arm.hpp"
#include "validate/record.hpp"

namespace {

void usage(std::FILE* to) {
  std::fprintf(to, "usage: truth_arm_record [--arm 2|3|6] [KEY=VALUE ...] --out FILE.csv\n\nfields (default values):\n");
  for (const auto& f : ff::truth::list_truth_arm_fields(ff::truth::TruthArm{}))
    std::fprintf(to, "  %-34s %-14s %s\n", f.name.c_str(), f.unit.c_str(), f.value.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  ff::truth::TruthArm arm;
  std::string out;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      usage(stdout);
      return 0;
    }
    if (arg == "--out" || arg == "--arm") {
      if (i + 1 == argc) {
        std::fprintf(stderr, "truth_arm_record: %s needs a value\n", arg.c_str());
        return 2;
      }
      const std::string v = argv[++i];
      if (arg == "--out") {
        out = v;
        continue;
      }
      try {
        if (i != 2) throw std::invalid_argument("--arm must come first (it resets every field)");
        if (v != "2" && v != "3" && v != "6") throw std::invalid_argument("--arm: '" + v + "' is not 2, 3 or 6");
        arm = ff::truth::make_suite_arm(std::stoi(v));
      } catch (const std::invalid_argument& e) {
        std::fprintf(stderr, "truth_arm_record: %s\n", e.what());
        return 2;
      }
      continue;
    }
    const auto eq = arg.find('=');
    if (eq == std::string::npos || eq == 0) {
      std::fprintf(stderr, "truth_arm_record: expected KEY=VALUE, --arm N or --out FILE, got '%s' (--help lists the keys)\n",
                   arg.c_str());
      return 2;
    }
    try {
      ff::truth::set_truth_arm_field(arm, arg.substr(0, eq), arg.substr(eq + 1));
    } catch (const std::invalid_argument& e) {
      std::fprintf(stderr, "truth_arm_record: %s (--help lists the keys)\n", e.what());
      return 2;
    }
  }
  if (out.empty()) {
    std::fprintf(stderr, "truth_arm_record: --out FILE.csv is required\n");
    return 2;
  }
  try {
    const ff::truth::TruthArmRun run = ff::truth::run_truth_arm(arm);
    ff::write_record_csv(run.record, ff::truth::truth_arm_record_columns(arm), out);
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "truth_arm_record: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "truth_arm_record: %s\n", e.what());
    return 1;
  }
  return 0;
}

// results/table.cpp: the per-run Markdown table writes a move that did not settle with its horizon.
#include "results/table.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace ff {
namespace {

const double kNaN = std::nan("");

TEST(Table, SettlingTableShowsTheHorizonOfANotSettledMove) {
  ResultTable t;
  t.columns = {"m1_tip_settling_s", "m1_tip_overshoot_pct", "m1_hub_settling_s", "m1_hub_overshoot_pct",
               "m1_peak_tip_deflection_m", "m1_residual_vibration_m", "m1_peak_torque_Nm", "m1_settling_horizon_s"};
  t.rows.resize(2);
  t.rows[0].label = "PD";
  t.rows[0].values = {kNaN, 38.0, 1.5, 6.7, 0.66, 0.62, 3880, 3.35};
  t.rows[1].label = "no horizon";
  t.rows[1].values = {kNaN, 38.0, kNaN, 6.7, 0.66, 0.62, 3880, kNaN};  // e.g. a diverged run: the plain words
  const std::string md = format_settling_table_md(t, {{"0 -> 0.5 rad"}, {"0 -> 0.5 rad"}});
  EXPECT_NE(md.find("| PD | 0 -> 0.5 rad | > 3.35 (not settled) | 38.0 | 1.50 | 6.7 | 660.0 | 620.00 | 3.88 |"),
            std::string::npos) << md;
  EXPECT_NE(md.find("| no horizon | 0 -> 0.5 rad | not settled | 38.0 | not settled |"), std::string::npos) << md;
}

}  // namespace
}  // namespace ff

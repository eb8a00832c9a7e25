// Measurement records (validate/record.cpp): bad records get one clear error naming file, line, column.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "common/errors.hpp"
#include "validate/record.hpp"

namespace ff {
namespace {

namespace fs = std::filesystem;

class Records : public ::testing::Test {
 protected:
  fs::path dir = fs::temp_directory_path() / ("ff_record_" + std::to_string(::getpid()));
  void SetUp() override { fs::create_directories(dir); }
  void TearDown() override { fs::remove_all(dir); }
  // A record of n rows: t = k/100, hub_angle = 0.01 k, hub_torque = 1, with `edit` applied to row `row`.
  std::string write(int n, const std::string& header = "t,hub_angle,hub_torque", int row = -1,
                    const std::string& edit = "") {
    const auto path = (dir / "r.csv").string();
    std::ofstream out(path);
    out << header << "\n";
    for (int k = 0; k < n; ++k) {
      if (k == row) {
        out << edit << "\n";
        continue;
      }
      out << k / 100.0 << "," << 0.01 * k << ",1\n";
    }
    return path;
  }
  static ConfigError error_of(const std::string& path, std::vector<std::string> required = {"hub_angle"}) {
    try {
      read_record_csv(path, required);
    } catch (const ConfigError& e) {
      return e;
    }
    ADD_FAILURE() << "accepted";
    return ConfigError("", 0, "", "");
  }
};

TEST_F(Records, GoodRecordReadsEveryColumn) {
  const Record r = read_record_csv(write(50), {"hub_angle", "hub_torque"});
  ASSERT_EQ(r.size(), 50u);
  EXPECT_DOUBLE_EQ(r.t[10], 0.1);
  EXPECT_DOUBLE_EQ(r.at("hub_angle")[10], 0.1);
  EXPECT_TRUE(r.has("hub_torque"));
  EXPECT_DOUBLE_EQ(interpolate(r.t, r.at("hub_angle"), 0.105), 0.105);
}

TEST_F(Records, MissingColumnIsNamed) {
  const auto e = error_of(write(50), {"ref"});
  EXPECT_EQ(e.line(), 1);
  EXPECT_EQ(e.key(), "ref");
}

TEST_F(Records, AByteOrderMarkBeforeTheHeaderIsSkipped) {
  // As a spreadsheet program saves CSV as "UTF-8": the mark would join the name of the first column, 't'.
  const Record r = read_record_csv(write(50, "\xEF\xBB\xBFt,hub_angle,hub_torque"), {"hub_angle", "hub_torque"});
  ASSERT_EQ(r.size(), 50u);
  EXPECT_DOUBLE_EQ(r.t[10], 0.1);
  EXPECT_DOUBLE_EQ(r.at("hub_angle")[10], 0.1);
}

TEST_F(Records, TwoColumnsOfOneNameAreRefusedNotReadLastWins) {
  // hub_angle,hub_torque and the torque again: compare would fit whichever column came last.
  const auto path = (dir / "r.csv").string();
  {
    std::ofstream out(path);
    out << "t,hub_torque,hub_angle,hub_torque\n";
    for (int k = 0; k < 50; ++k) out << k / 100.0 << ",1," << 0.01 * k << ",-1\n";
  }
  const auto e = error_of(path);
  EXPECT_STREQ(e.what(), (path + ":1: hub_torque: columns 2 and 4 are both named 'hub_torque': each column needs "
                                 "its own name").c_str());
}

TEST_F(Records, TimeThatDoesNotIncreaseNamesItsLine) {
  const auto e = error_of(write(50, "t,hub_angle,hub_torque", 5, "0.03,0.05,1"));
  EXPECT_EQ(e.line(), 7);
  EXPECT_EQ(e.key(), "t");
}

TEST_F(Records, NanAndEmptyCellsNameLineAndColumn) {
  auto e = error_of(write(50, "t,hub_angle,hub_torque", 8, "0.08,nan,1"));
  EXPECT_EQ(e.line(), 10);
  EXPECT_EQ(e.key(), "hub_angle");
  // An empty cell in the first row: a channel logged slower still needs its first value.
  e = error_of(write(50, "t,hub_angle,hub_torque", 0, "0,0,"));
  EXPECT_EQ(e.line(), 2);
  EXPECT_EQ(e.key(), "hub_torque");
  EXPECT_NE(e.message().find("empty cell in the first row"), std::string::npos);
  // Time is never empty.
  e = error_of(write(50, "t,hub_angle,hub_torque", 8, ",0.08,1"));
  EXPECT_EQ(e.line(), 10);
  EXPECT_EQ(e.key(), "t");
}

// A channel logged slower than the rows (a 20 Hz torque beside a 100 Hz angle): empty cells hold the last value.
TEST_F(Records, EmptyCellsOfASlowerChannelHoldItsLastValue) {
  const auto path = (dir / "r.csv").string();
  {
    std::ofstream out(path);
    out << "t,hub_angle,hub_torque\n";
    for (int k = 0; k < 50; ++k) {
      out << k / 100.0 << "," << 0.01 * k << ",";
      if (k % 5 == 0) out << k;
      out << "\n";
    }
  }
  const Record r = read_record_csv(path, {"hub_angle", "hub_torque"});
  for (int k = 0; k < 50; ++k) EXPECT_EQ(r.at("hub_torque")[k], k / 5 * 5) << k;
  EXPECT_EQ(r.held.at("hub_torque"), 40u);
  EXPECT_EQ(r.held.count("hub_angle"), 0u);
}

TEST_F(Records, TooFewSamplesAreRefusedAtTheLastLine) {
  const auto e = error_of(write(5));
  EXPECT_NE(e.message().find("only 5 samples"), std::string::npos);
  EXPECT_EQ(e.line(), 6);  // the header and five rows
  EXPECT_EQ(e.key(), "t");
}

TEST_F(Records, DegreesWhereRadiansAreExpectedAreRefused) {
  const auto path = (dir / "deg.csv").string();
  std::ofstream out(path);
  out << "t,hub_angle\n";
  for (int k = 0; k < 50; ++k) out << k / 100.0 << "," << 0.5 * k << "\n";  // 0 .. 24.5 "rad"
  out.close();
  const auto e = error_of(path);
  EXPECT_EQ(e.key(), "hub_angle");
  EXPECT_EQ(e.line(), 15);  // sample 13: 6.5 "rad" from 0, the first swing beyond 2 pi
  EXPECT_NE(e.message().find("degrees"), std::string::npos);
}

TEST_F(Records, HubRateInDegreesPerSecondIsRefused) {
  // A hub turning at 0.02 rad/s (0 .. 0.098 rad over the record), its rate written in deg/s (1.15):
  // the rate's integral swings 57 times as far as the angle.
  const auto path = (dir / "rate.csv").string();
  std::ofstream out(path);
  out << "t,hub_angle,hub_rate\n";
  for (int k = 0; k < 50; ++k) out << k / 10.0 << "," << 0.002 * k << "," << 0.02 * 180.0 / M_PI << "\n";
  out.close();
  const auto e = error_of(path);
  EXPECT_EQ(e.key(), "hub_rate");
  EXPECT_EQ(e.line(), 11);  // the integral passes 10 x 0.098 rad at t = 0.9 s (sample 9: 1.03)
  EXPECT_NE(e.message().find("degrees per second"), std::string::npos);
  // The same rate in rad/s is fine.
  std::ofstream good(path);
  good << "t,hub_angle,hub_rate\n";
  for (int k = 0; k < 50; ++k) good << k / 10.0 << "," << 0.002 * k << "," << 0.02 << "\n";
  good.close();
  EXPECT_EQ(read_record_csv(path, {"hub_rate"}).size(), 50u);
}

TEST_F(Records, RaggedRowIsRefused) {
  const auto e = error_of(write(50, "t,hub_angle,hub_torque", 3, "0.03,0.03"));
  EXPECT_EQ(e.line(), 5);
}


// A reference of rest-to-rest moves r0 + D (3u^2 - 2u^3), u = (t - ts) / T, and holds: exact value, rate and
// acceleration (the acceleration jumps by 6 D / T^2 at each move's start and end).
struct MoveProfile {
  struct Move { double start, T, from, to; };
  std::vector<Move> moves;
  double at(double t, int d) const {
    double r = moves.empty() ? 0.0 : moves.front().from;
    double v = 0.0, a = 0.0;
    for (const Move& m : moves) {
      if (t < m.start) break;
      const double D = m.to - m.from;
      if (t >= m.start + m.T) { r = m.to; v = a = 0.0; continue; }
      const double u = (t - m.start) / m.T;
      r = m.from + D * u * u * (3 - 2 * u);
      v = D * 6 * u * (1 - u) / m.T;
      a = D * 6 * (1 - 2 * u) / (m.T * m.T);
    }
    return d == 0 ? r : d == 1 ? v : a;
  }
};

// sample_piecewise_smooth against the moves' own derivatives: 30 references drawn at random (1-4 moves of
// 0.3-4 s, holds of none or 0.1-3 s, knots anywhere between samples, records at 100-1000 Hz), read at
// 1 kHz. The acceleration is within 2 % of its peak a everywhere (a knot a few hundredths of a sample
// from a sample is not told from a smooth bend) and within 1e-3 a in RMS, the value and rate within
// 0.2 a h^2 and 0.2 a h; central differences, which it replaced, are off by a third of a or more at the knots.
TEST(PiecewiseSmooth, MovesAreReadWithTheirAccelerationJumpsAtTheKnots) {
  std::uint64_t state = 20261207;
  auto uniform = [&](double lo, double hi) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return lo + (hi - lo) * static_cast<double>(state >> 11) * 0x1.0p-53;
  };
  double worst_central = 0.0;
  for (int c = 0; c < 30; ++c) {
    MoveProfile prof;
    double t = uniform(0.0, 0.7), at = 0.0;
    const int moves = 1 + static_cast<int>(uniform(0, 4));
    for (int m = 0; m < moves; ++m) {
      const double to = at + (uniform(0, 1) < 0.5 ? -1 : 1) * uniform(0.1, 1.0), T = uniform(0.3, 4.0);
      prof.moves.push_back({t, T, at, to});
      at = to;
      t += T + (uniform(0, 1) < 0.3 ? 0.0 : uniform(0.1, 3.0));
    }
    const double h = 1.0 / uniform(100, 1000), end = t + 0.5;
    std::vector<double> ts, ys;
    for (double x = 0.0; x <= end; x += h) ts.push_back(x), ys.push_back(prof.at(x, 0));
    double peak = 0.0;
    for (const auto& m : prof.moves) peak = std::max(peak, 6 * std::abs(m.to - m.from) / (m.T * m.T));
    const double T = 1e-3;
    const long n = static_cast<long>((ts.back() - ts.front()) / T) + 1;
    const SmoothSamples s = sample_piecewise_smooth(ts, ys, ts.front(), T, n);
    const auto rate = time_derivative(ts, ys), accel = time_derivative(ts, rate);
    double e2 = 0.0;
    for (long k = 0; k < n; ++k) {
      const double x = static_cast<double>(k) * T;
      ASSERT_NEAR(s.value[k], prof.at(x, 0), 0.2 * peak * h * h) << "case " << c << " t " << x;
      ASSERT_NEAR(s.rate[k], prof.at(x, 1), 0.2 * peak * h) << "case " << c << " t " << x;
      ASSERT_NEAR(s.accel[k], prof.at(x, 2), 0.02 * peak) << "case " << c << " t " << x << " h " << h;
      e2 += std::pow((s.accel[k] - prof.at(x, 2)) / peak, 2);
      worst_central = std::max(worst_central, std::abs(interpolate(ts, accel, x) - prof.at(x, 2)) / peak);
    }
    EXPECT_LT(std::sqrt(e2 / n), 1e-3) << "case " << c;
  }
  EXPECT_GT(worst_central, 0.3);
}

// A smooth signal without knots (a sine) is read to the cubic's accuracy, O(h^2) in the acceleration; a
// record on the controller's own grid gives its samples exactly.
TEST(PiecewiseSmooth, ASmoothSignalIsReadToTheCubicsAccuracy) {
  std::vector<double> ts, ys;
  const double h = 0.005, w = 2.0;
  for (int k = 0; k <= 800; ++k) ts.push_back(k * h), ys.push_back(std::sin(w * k * h));
  const SmoothSamples s = sample_piecewise_smooth(ts, ys, 0.0, 1e-3, 4001);
  for (long k = 0; k < 4001; ++k) {
    const double x = k * 1e-3;
    ASSERT_NEAR(s.value[k], std::sin(w * x), 1e-8) << x;
    ASSERT_NEAR(s.rate[k], w * std::cos(w * x), 1e-6) << x;
    ASSERT_NEAR(s.accel[k], -w * w * std::sin(w * x), 1e-3) << x;
  }
  const SmoothSamples on = sample_piecewise_smooth(ts, ys, 0.0, h, 801);
  EXPECT_EQ(on.value, ys);
}

}  // namespace
}  // namespace ff

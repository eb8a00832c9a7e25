// Values whose unit is easily mistaken (common/units_check.hpp): the edges of each range, and the
// likely mistake each message names (issue 32, item 10).
#include "common/units_check.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace {

TEST(UnitsCheck, AnAngleBeyondATurnLooksLikeDegrees) {
  EXPECT_EQ(ff::explain_angle_unit(0.0), "");
  EXPECT_EQ(ff::explain_angle_unit(2.0 * M_PI), "");   // a turn exactly (a URDF's +-2 pi limits)
  EXPECT_EQ(ff::explain_angle_unit(-6.28318530718), "");  // 2 pi as URDFs round it
  EXPECT_EQ(ff::explain_angle_unit(6.2832), "");
  EXPECT_EQ(ff::explain_angle_unit(57.0).rfind("57 rad is more than a turn (2 pi): looks like degrees (57 deg = 0.9948 rad)", 0), 0u);
  EXPECT_NE(ff::explain_angle_unit(-6.3).find("(-6.3 deg = -0.11 rad)"), std::string::npos);
  EXPECT_NE(ff::explain_angle_unit(90.0).find("set `units_check: false` at the top of the file"), std::string::npos);
}

TEST(UnitsCheck, AModulusOutsideEveryMaterialLooksLikeGpaOrMpa) {
  for (double ok : {1e6, 3e9, 70e9, 207e9, 1.2e12, 2e12}) EXPECT_EQ(ff::explain_modulus_unit(ok), "") << ok;
  EXPECT_EQ(ff::explain_modulus_unit(70.0).rfind(
                "70 Pa is far below any engineering material (1e6 to 2e12 Pa): looks like GPa (70 GPa = 7e+10 Pa)", 0),
            0u);
  EXPECT_NE(ff::explain_modulus_unit(70000.0).find("looks like MPa (7e+04 MPa = 7e+10 Pa)"), std::string::npos);
  EXPECT_NE(ff::explain_modulus_unit(2.1e14).find("far above"), std::string::npos);
}

TEST(UnitsCheck, ADensityOutsideEveryMaterialLooksLikeGramsPerCubicCentimetre) {
  for (double ok : {0.0, 50.0, 1600.0, 7850.0, 22590.0, 25000.0}) EXPECT_EQ(ff::explain_density_unit(ok), "") << ok;
  EXPECT_EQ(ff::explain_density_unit(7.85).rfind(
                "7.85 kg/m³ is far below any engineering material (50 to 25000 kg/m³): looks like g/cm³ (7.85 g/cm³ = 7850 kg/m³)", 0),
            0u);
  EXPECT_NE(ff::explain_density_unit(7.85e6).find("far above"), std::string::npos);
}

}  // namespace

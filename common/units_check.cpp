#include "common/units_check.hpp"

#include <cmath>
#include <sstream>

namespace ff {

namespace {
std::string number(double x) {
  std::ostringstream o;
  o.precision(4);
  o << x;
  return o.str();
}
constexpr const char* kMeant = " (if it is meant, set `units_check: false` at the top of the file)";
}  // namespace

std::string explain_angle_unit(double rad) {
  if (!(std::abs(rad) > 2.0 * M_PI * (1.0 + 1e-3))) return "";  // 2 pi as files round it (6.2832) passes
  return number(rad) + " rad is more than a turn (2 pi): looks like degrees (" + number(rad) + " deg = " +
         number(rad * M_PI / 180.0) + " rad); angles are in radians" + kMeant;
}

std::string explain_modulus_unit(double pa) {
  constexpr double kLow = 1e6, kHigh = 2e12;  // Pa: soft rubber, above diamond's 1.2e12
  if (pa >= kLow && pa <= kHigh) return "";
  const std::string range = " any engineering material (1e6 to 2e12 Pa)";
  if (pa > kHigh) return number(pa) + " Pa is far above" + range + ": check its unit; moduli are in Pa" + kMeant;
  const char* unit = pa * 1e9 <= kHigh ? "GPa" : "MPa";
  const double scale = pa * 1e9 <= kHigh ? 1e9 : 1e6;
  return number(pa) + " Pa is far below" + range + ": looks like " + unit + " (" + number(pa) + " " + unit + " = " +
         number(pa * scale) + " Pa); moduli are in Pa" + kMeant;
}

std::string explain_density_unit(double kg_m3) {
  constexpr double kLow = 50.0, kHigh = 25000.0;  // kg/m³: rigid foam, above osmium's 22590
  if (kg_m3 == 0.0 || (kg_m3 >= kLow && kg_m3 <= kHigh)) return "";
  const std::string range = " any engineering material (50 to 25000 kg/m³)";
  if (kg_m3 > kHigh) return number(kg_m3) + " kg/m³ is far above" + range + ": check its unit" + kMeant;
  return number(kg_m3) + " kg/m³ is far below" + range + ": looks like g/cm³ (" + number(kg_m3) + " g/cm³ = " +
         number(kg_m3 * 1000.0) + " kg/m³); densities are in kg/m³" + kMeant;
}

}  // namespace ff

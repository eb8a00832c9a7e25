// Values whose unit is easily mistaken (degrees for radians, GPa for Pa, g/cm³ for kg/m³), checked where a
// model is read unless its file says `units_check: false` (docs/formats.md): each returns "" when the value
// is plausible, else why not, naming the likely mistake.
#pragma once

#include <string>

namespace ff {

// A revolute joint's angle (target, waypoint, start, limit), rad: beyond a turn (2 pi) it looks like degrees.
std::string explain_angle_unit(double rad);
// An elastic modulus (Young's E, shear G), Pa: outside [1e6, 2e12] Pa (rubber to diamond) it looks like GPa
// or MPa.
std::string explain_modulus_unit(double pa);
// A density, kg/m³: outside [50, 25000] kg/m³ (foam to osmium) it looks like g/cm³; 0 (massless) passes.
std::string explain_density_unit(double kg_m3);

}  // namespace ff

// Input shapers on the reference (Singer & Seering 1990; Singhose, Seering & Singer 1994):
// r_shaped(t) = sum_i A_i r(t - t_i), impulses that cancel (ZV, ZVD) or bound (EI) the residual
// vibration of a mode of frequency omega and damping zeta. The reference is a known function of
// time, so shaping it is exact: no discretisation.
#pragma once

#include <vector>

namespace ff {

enum class ShaperKind { kNone, kZv, kZvd, kEi };

struct Impulse {
  double time;       // s, from the start of the command
  double amplitude;  // dimensionless; a shaper's amplitudes sum to 1
};

// The impulses of a shaper for a mode (omega rad/s, 0 <= zeta < 1). EI: vtol is the residual
// vibration allowed at the design frequency (typically 0.05). Throws std::invalid_argument on bad
// arguments.
std::vector<Impulse> make_shaper(ShaperKind kind, double omega, double zeta, double vtol = 0.05);

// Residual vibration of a mode (omega, zeta) after a shaped step, relative to the unshaped step's
// (Singer & Seering 1990, eq. 6): 1 = no effect, 0 = cancelled.
double calc_residual_vibration(const std::vector<Impulse>& shaper, double omega, double zeta);

// Width of the band of frequencies, relative to the design frequency, around it where the residual
// vibration stays <= level (the shaper's insensitivity).
double calc_insensitivity(const std::vector<Impulse>& shaper, double design_omega, double zeta, double level = 0.05);

}  // namespace ff

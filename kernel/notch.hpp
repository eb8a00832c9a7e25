// The robust notch filter of seed eq. 6 acting on the reference signal, and its discrete
// realisation as a cascade of second-order sections (Tustin's method with pre-warping, Franklin,
// Powell & Workman, Digital Control of Dynamic Systems, "Discrete Equivalents"), advanced for W lanes at once.
#pragma once

#include <complex>
#include <vector>

namespace ff {

struct NotchDesign {            // continuous filter of seed eq. 6
  int order = 1;                // n >= 1
  double omega_z[2];            // zeros, rad/s
  double alpha[2];              // omega_p = alpha * omega_z
  double zeta[2];               // pole damping ratios
};

// One discrete second-order section y = (b0 + b1 z^-1 + b2 z^-2)/(1 + a1 z^-1 + a2 z^-2) x.
struct Biquad { double b0, b1, b2, a1, a2; };

// F(j omega) of eq. 6.
std::complex<double> calc_notch_response(const NotchDesign& d, double omega);

// The cascade of 2n+1 sections that realises eq. 6 at sample period T (s):
// n sections (omega_z1 / omega_p1), n sections (omega_z2 / omega_p2), one low-pass (1 / omega_p2),
// each with DC gain 1, each pre-warped at its own zero frequency (the low-pass at its pole frequency).
// Every omega_z and omega_p must satisfy omega * period <= pi/2 (a quarter of the sample rate).
std::vector<Biquad> make_notch_sections(const NotchDesign& d, double period);

// Frequency response of a cascade at omega (rad/s), z = exp(j omega T).
std::complex<double> calc_sections_response(const std::vector<Biquad>& s, double omega, double period);

// Advance W independent filters (lanes) by one sample. Layout, structure-of-arrays with the lane innermost:
// coef[(5*k + c)*W + lane] = coefficient c (b0,b1,b2,a1,a2) of section k, state[(2*k + j)*W + lane] (j = 0,1),
// in[lane] the input sample, out[lane] the output sample. Transposed direct form II. Must not allocate.
// in and out may be the same array (but must not overlap otherwise).
void step_notch(int nsections, int W, const double* coef, double* state, const double* in, double* out);

// Fill coef (5*nsections*W) for lane `lane` from sections.
void pack_notch_sections(const std::vector<Biquad>& s, int W, int lane, double* coef);

// State for a filter resting at input value x0 (steady state: every section's output = x0), lane `lane`.
void reset_notch_state(int nsections, int W, int lane, const double* coef, double x0, double* state);

}  // namespace ff

// Global sensitivity analysis of a study's responses: Sobol' indices from a Saltelli design, and Morris
// elementary effects. The designs themselves are generated elsewhere; these functions only read their layout.
#pragma once

#include <cstdint>
#include <vector>

namespace ff {

// Sobol' indices from a Saltelli design with N base samples and d inputs. Layout of the evaluations y (length
// N (d+2), else std::invalid_argument), fixed by the design generator: y[0..N) = f(A), y[N..2N) = f(B),
// y[(2+i)N .. (3+i)N) = f(AB_i) where AB_i is A with column i taken from B, i = 0..d-1.
//   first order  S_i  = V_i / V,  V_i = mean_k f(B)_k (f(AB_i)_k - f(A)_k)     (Saltelli et al. 2010, Table 2 b)
//   total        ST_i = E_i / V,  E_i = mean_k (f(A)_k - f(AB_i)_k)^2 / 2     (Jansen 1999; Saltelli 2010 Table 2 f)
//   V = population variance of the 2N values [f(A), f(B)]                     (as SALib)
// first_ci / total_ci: 95 % half-widths, 1.96 x the sample standard deviation of the index over `resamples`
// bootstrap resamples of the base index k (the same k for every block and every i, as SALib); NaN if
// resamples < 2. Deterministic in `seed` (draw j of resample b is draw_index(seed, b n + j, n)).
// NaN policy: a base index k with a NaN in any block (f(A)_k, f(B)_k or any f(AB_i)_k) is dropped from all
// blocks; the indices use the n kept base indices. Fewer than 2 kept, or V = 0 -> NaN indices.
struct SobolIndices {
  std::vector<double> first, total, first_ci, total_ci;
};
SobolIndices calc_sobol_indices(const std::vector<double>& y, int d, int resamples, std::uint64_t seed);

// Morris elementary effects (Morris 1991; mu* of Campolongo, Cariboni & Saltelli 2007). Layout: r trajectories
// of d+1 consecutive rows each; consecutive rows of a trajectory differ in exactly one variable (by more than
// 1e-9), and each variable changes exactly once per trajectory (else std::invalid_argument). x_unit holds the
// design in the unit cube (rows x d), y the response per row. The elementary effect of the step from row j to
// j+1 changing variable i is (y[j+1] - y[j]) / (x[j+1][i] - x[j][i]), so in unit-cube scale.
//   mu = mean EE, mu_star = mean |EE|, sigma = sample standard deviation of EE (divisor count - 1, as SALib).
// NaN policy: an elementary effect with a NaN y at either end is dropped; a variable with no effects left
// has NaN mu / mu_star / sigma (sigma NaN with fewer than 2).
struct MorrisIndices {
  std::vector<double> mu, mu_star, sigma;
};
MorrisIndices calc_morris_indices(const std::vector<std::vector<double>>& x_unit, const std::vector<double>& y, int d);

}  // namespace ff

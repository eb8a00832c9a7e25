// Experimental designs of a study (sweep/): which parameter values each evaluation gets.
//
// A design is a matrix: rows = evaluations (row r becomes eval_id r), columns = variables in the order
// given, values in the variables' own units. Every design is a pure function of (DesignSpec, variables):
// the same call gives the same bits on any machine, thread count or rank count (all randomness comes from
// common/random.hpp's counter-based streams keyed by spec.seed).
//
// Row layouts (the result and sensitivity code elsewhere relies on them):
//   grid        full factorial over each variable's `levels`; the LAST variable varies fastest:
//               row r = sum_j idx_j * prod_{k>j} n_k, so (a: {1,2}, b: {10,20,30}) gives
//               (1,10) (1,20) (1,30) (2,10) (2,20) (2,30).
//   centered    Dakota's centered_parameter_study, one at a time: row 0 all nominal; then for each
//               variable in order one row per level (in the order given) with every other variable at
//               nominal. Levels equal to the nominal, and repeats of a level, are skipped.
//   monte_carlo row i, variable j: calc_quantile(dist_j, u_ij), u_i0, u_i1, ... the uniforms of
//               CounterRng(calc_variant_seed(seed, i)) in variable order. Row i does not depend on how
//               many samples there are.
//   lhs         Latin hypercube (make_latin_hypercube) mapped by the quantiles.
//   sobol       scrambled Sobol' points (make_sobol_points) mapped by the quantiles.
//   saltelli    d variables, base size N = spec.samples. One 2d-dimensional scrambled Sobol' set of N
//               points (make_sobol_points(N, 2d, seed)): A = its first d columns, B = its last d. Rows:
//                 [0, N)                A
//                 [N, 2N)               B
//                 [(2+i)N, (3+i)N)      AB_i for i = 0..d-1: A with column i taken from B,
//               N(d+2) rows in total: row (2+i)N + k equals row k of A except column i, which equals row
//               k of B. All mapped by the quantiles (Saltelli et al. 2010, Comput. Phys. Commun. 181).
//   morris      r = spec.trajectories trajectories of d+1 rows each on the p-level grid
//               {0, 1/(p-1), ..., 1}, p = spec.morris_levels even, step Delta = p / (2(p-1)) (Morris 1991;
//               Campolongo, Cariboni & Saltelli 2007). Rows t(d+1) .. t(d+1)+d are trajectory t. Per
//               trajectory: a random base point x* with every coordinate in {0, ..., p/2-1}/(p-1) (so
//               x* + Delta <= 1), a random direction +1/-1 per variable and a random order of the
//               variables. Row 0 has x*_j where the direction is +1 and x*_j + Delta where it is -1; row k
//               (k = 1..d) changes exactly one variable, the k-th in the order, by +Delta or -Delta. So the
//               variable changed at step k, and by how much, is the one column that differs between rows
//               t(d+1)+k-1 and t(d+1)+k. Grid values u in [0, 1] map through calc_quantile; for a variable
//               with unbounded support (normal, lognormal, truncated normal with an infinite bound) u is
//               first clipped to [1e-12, 1 - 1e-12]; bounded ones (uniform, choice, finite truncated
//               normal) map u = 0, 1 to their bounds exactly.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace ff {

enum class DistributionKind { kUniform, kNormal, kTruncatedNormal, kLognormal, kChoice };

struct Distribution {
  DistributionKind kind = DistributionKind::kUniform;
  double lower = 0, upper = 1;  // uniform bounds; truncated-normal bounds (may be -inf / +inf)
  double mean = 0, std = 1;     // normal and truncated normal (of the parent normal)
  double mu = 0, sigma = 1;     // lognormal: log X ~ N(mu, sigma)
  std::vector<double> values;   // choice
  std::vector<double> weights;  // choice; empty = equal
};

// Inverse CDF at u in [0, 1]. u = 0 and 1 give the support's ends: the bounds of uniform and truncated
// normal, the first / last value of positive weight of choice, -inf / +inf for normal, 0 / +inf for
// lognormal. Truncated normal: Phi^-1 of Phi(a) + u (Phi(b) - Phi(a)), worked in the upper tail's
// complement when a >= 0 so far-tail truncations keep their precision. Choice: the first value whose
// cumulative weight exceeds u * total. Throws std::invalid_argument for u outside [0, 1].
double calc_quantile(const Distribution& d, double u);

// Throws std::invalid_argument with a message naming the kind and the offending field.
void validate_distribution(const Distribution& d);

struct Variable {
  std::string path;             // model parameter, e.g. "payload.mass"
  Distribution dist;            // for monte_carlo, lhs, sobol, saltelli, morris
  std::vector<double> levels;   // for grid and centered: the values to visit
  double nominal = 0;           // for centered: the centre point
};

enum class DesignKind { kGrid, kCentered, kMonteCarlo, kLatinHypercube, kSobol, kSaltelli, kMorris };

struct DesignSpec {
  DesignKind kind = DesignKind::kGrid;
  int samples = 0;         // monte_carlo, lhs, sobol; saltelli: base sample count N
  int trajectories = 0;    // morris: r
  int morris_levels = 4;   // morris: p (even)
  std::uint64_t seed = 0;
};

// Most dimensions of the embedded Joe & Kuo table, so sobol takes at most this many variables and
// saltelli at most half of it.
inline constexpr int kSobolMaxDimension = 100;

// Checks the spec and the variables the design kind uses (std::invalid_argument naming the variable):
// no variables, samples / trajectories < 1, grid variable without levels, non-finite levels or nominal,
// Morris p odd or < 2, a bad distribution, too many Sobol' dimensions, more than INT_MAX rows.
void validate_design(const DesignSpec& spec, const std::vector<Variable>& vars);

// Number of rows make_design returns (validates first).
int calc_design_size(const DesignSpec& spec, const std::vector<Variable>& vars);

// Rows = evaluations, columns = variables, values in the variables' units; layouts above.
std::vector<std::vector<double>> make_design(const DesignSpec& spec, const std::vector<Variable>& vars);

// Unit-cube point sets, n rows x d columns, entries in (0, 1).
// Latin hypercube (McKay, Beckman & Conover 1979): column j puts row i in stratum perm_j(i) of n equal
// strata, at a uniform position inside it; perm_j and the positions come from a stream keyed by (seed, j).
std::vector<std::vector<double>> make_latin_hypercube(int n, int d, std::uint64_t seed);

// Scrambled Sobol' points, rows = sequence indices 0..n-1 in Gray-code order (nothing skipped), d <=
// kSobolMaxDimension. Direction numbers: Joe & Kuo, new-joe-kuo-6.21201 (SIAM J. Sci. Comput. 30, 2008).
// Scramble: Owen's nested uniform scramble (Owen 1995), with the random flip of every node of the
// binary digit tree drawn by hashing (dimension key, node) with SplitMix64 - the hash-based formulation of
// Burley 2020 ("Practical hash-based Owen scrambling", JCGT 9(4)), with one full hash per digit rather than
// the Laine-Karras approximation. The 32 scrambled digits are followed by 20 random digits (the scramble
// of the remaining, all-zero digits), so points fill their cell; each dimension's key derives from
// (seed, dimension). Nested scrambling keeps the net property: for n = 2^m, each column has one point in
// every [k 2^-m, (k+1) 2^-m), and a projection that is a (t, m, s)-net stays one.
std::vector<std::vector<double>> make_sobol_points(int n, int d, std::uint64_t seed);

// The unscrambled sequence (Joe & Kuo's sobol.cc): row 0 is the origin, then x_i = XOR of the direction
// numbers V_k for the set bits k of gray(i) = i ^ (i >> 1), over 2^32; entries in [0, 1). Dimension 1
// reads 0, 0.5, 0.75, 0.25, 0.375, 0.875, ...
std::vector<std::vector<double>> make_sobol_points_unscrambled(int n, int d);

// Morris step on the p-level grid: p / (2 (p - 1)).
double calc_morris_delta(int p);

// Morris trajectories on the unit grid: r(d+1) rows of grid values in [0, 1], layout as for the morris
// design above (make_design maps these through the quantiles). Trajectory t draws from a stream keyed by
// (seed, t), so it does not depend on r.
std::vector<std::vector<double>> make_morris_points(int r, int d, int p, std::uint64_t seed);

}  // namespace ff

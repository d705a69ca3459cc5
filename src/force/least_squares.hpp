// Bounded nonlinear least squares (Ceres), behind the plugin libtrochomill_ceres.so
// (least_squares_plugin.cpp): linked into the program, Ceres and what it brings (glog,
// SuiteSparse, LAPACK) cost every start about 9 ms. The calibration's one use of it.
#pragma once

#include <functional>
#include <string>
#include <vector>

namespace trochomill::force_detail {

/// A problem: residuals of parameter blocks within bounds, their derivatives by central
/// differences, solved by Levenberg-Marquardt with a dense QR.
struct LeastSquaresCall {
  std::vector<double*> blocks;                    ///< the parameters (changed in place)
  std::vector<int> block_sizes;                   ///< entries of each block
  std::vector<std::vector<double>> lower, upper;  ///< per block, per entry
  int residuals = 0;                              ///< how many fn writes
  /// The residuals of the blocks' values; false: this point cannot be evaluated.
  std::function<bool(double const* const* blocks, double* residuals)> fn;
  int max_iterations = 100;
  double function_tolerance = 1e-10, parameter_tolerance = 1e-10, gradient_tolerance = 1e-12;
  /// After each iteration (its number): false stops the solver.
  std::function<bool(int iteration)> keep_going;
};
/// What the solver ends with: the cost and residuals at the solution, the Jacobian there (rows
/// as compressed rows over the blocks' entries in order), the iterations, Ceres' brief report.
struct LeastSquaresResult {
  double final_cost = 0;
  std::vector<double> residuals;
  int jacobian_rows = 0;
  std::vector<int> jacobian_row_starts, jacobian_cols;
  std::vector<double> jacobian_values;
  int iterations = 0;
  std::string report;
};

/// The plugin's functions (trochomill_ceres_table()).
struct CeresTable {
  LeastSquaresResult (*solve)(const LeastSquaresCall& call);
};
inline constexpr const char* kCeresSymbol = "trochomill_ceres_table";

}  // namespace trochomill::force_detail

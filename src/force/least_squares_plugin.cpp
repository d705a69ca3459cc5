// The plugin libtrochomill_ceres.so (least_squares.hpp): Ceres' bounded Levenberg-Marquardt.
#include <ceres/ceres.h>

#include <cstddef>

#include "least_squares.hpp"

namespace trochomill::force_detail {
namespace {

// The call's residual function as Ceres' dynamic cost functor.
struct Residuals {
  const LeastSquaresCall* call;
  bool operator()(double const* const* x, double* r) const { return call->fn(x, r); }
};

// Stops the solver when the call says so.
class Iterations : public ceres::IterationCallback {
 public:
  explicit Iterations(const LeastSquaresCall& call) : call_(call) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
    if (call_.keep_going && !call_.keep_going(s.iteration)) return ceres::SOLVER_ABORT;
    return ceres::SOLVER_CONTINUE;
  }

 private:
  const LeastSquaresCall& call_;
};

LeastSquaresResult solve(const LeastSquaresCall& call) {
  auto* cost =
      new ceres::DynamicNumericDiffCostFunction<Residuals, ceres::CENTRAL>(new Residuals{&call});
  for (const int n : call.block_sizes) cost->AddParameterBlock(n);
  cost->SetNumResiduals(call.residuals);
  ceres::Problem cp;
  cp.AddResidualBlock(cost, nullptr, call.blocks);
  for (std::size_t b = 0; b < call.blocks.size(); ++b) {
    for (int i = 0; i < call.block_sizes[b]; ++i) {
      cp.SetParameterLowerBound(call.blocks[b], i, call.lower[b][static_cast<std::size_t>(i)]);
      cp.SetParameterUpperBound(call.blocks[b], i, call.upper[b][static_cast<std::size_t>(i)]);
    }
  }
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = call.max_iterations;
  so.function_tolerance = call.function_tolerance;
  so.parameter_tolerance = call.parameter_tolerance;
  so.gradient_tolerance = call.gradient_tolerance;
  so.num_threads = 1;
  so.logging_type = ceres::SILENT;
  Iterations callback(call);
  so.callbacks.push_back(&callback);
  ceres::Solver::Summary summary;
  ceres::Solve(so, &cp, &summary);
  LeastSquaresResult out;
  ceres::CRSMatrix jac;
  cp.Evaluate(ceres::Problem::EvaluateOptions(), &out.final_cost, &out.residuals, nullptr, &jac);
  out.jacobian_rows = jac.num_rows;
  out.jacobian_row_starts = jac.rows;
  out.jacobian_cols = jac.cols;
  out.jacobian_values = jac.values;
  out.iterations = static_cast<int>(summary.iterations.size());
  out.report = summary.BriefReport();
  return out;
}

const CeresTable kTable{&solve};

}  // namespace
}  // namespace trochomill::force_detail

extern "C" __attribute__((visibility("default"))) const trochomill::force_detail::CeresTable*
trochomill_ceres_table() {
  return &trochomill::force_detail::kTable;
}

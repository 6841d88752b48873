#include "flowfusion/slam/pose_graph.h"

#include <algorithm>
#include <string>

#include "flowfusion/core/error.h"

#ifdef FLOWFUSION_HAVE_CERES
#include <ceres/ceres.h>
#endif

namespace ff {

#ifdef FLOWFUSION_HAVE_CERES

namespace {

// One edge's whitened error over two nodes, each a translation (3) and a quaternion (x, y, z, w).
struct EdgeError {
  Eigen::Vector3d t_from_to;
  Eigen::Quaterniond q_from_to;
  double inv_sigma_m, inv_sigma_rad;

  template <class T>
  bool operator()(const T* t_a, const T* q_a, const T* t_b, const T* q_b, T* residual) const {
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> pa(t_a), pb(t_b);
    const Eigen::Map<const Eigen::Quaternion<T>> qa(q_a), qb(q_b);
    const Eigen::Quaternion<T> qa_inv = qa.conjugate();
    const Eigen::Quaternion<T> q_ab = qa_inv * qb;
    const Eigen::Matrix<T, 3, 1> p_ab = qa_inv * (pb - pa);
    const Eigen::Quaternion<T> q_err = q_from_to.template cast<T>().conjugate() * q_ab;
    const Eigen::Matrix<T, 3, 1> p_err = q_from_to.template cast<T>().conjugate() * (p_ab - t_from_to.template cast<T>());
    for (int i = 0; i < 3; ++i) {
      residual[i] = p_err[i] * T(inv_sigma_m);
      residual[3 + i] = T(2.0) * q_err.vec()[i] * T(inv_sigma_rad);
    }
    return true;
  }
};

}  // namespace

std::vector<SE3> optimizePoseGraph(const std::vector<SE3>& initial, const std::vector<PoseGraphEdge>& edges,
                                   const PoseGraphOptions& options) {
  const int n = static_cast<int>(initial.size());
  std::vector<Eigen::Vector3d> t(n);
  std::vector<Eigen::Quaterniond> q(n);
  for (int i = 0; i < n; ++i) {
    t[i] = initial[i].translation();
    q[i] = Eigen::Quaterniond(initial[i].linear()).normalized();
  }
  ceres::Problem problem;
  for (const PoseGraphEdge& e : edges) {
    if (e.from < 0 || e.from >= n || e.to < 0 || e.to >= n || e.from == e.to)
      throw InputError("pose graph: edge " + std::to_string(e.from) + " -> " + std::to_string(e.to) + " of " +
                       std::to_string(n) + " nodes");
    auto* cost = new ceres::AutoDiffCostFunction<EdgeError, 6, 3, 4, 3, 4>(
        new EdgeError{e.T_from_to.translation(), Eigen::Quaterniond(e.T_from_to.linear()).normalized(),
                      1.0 / e.sigma_m, 1.0 / e.sigma_rad});
    ceres::LossFunction* loss = e.robust_scale > 0 ? new ceres::CauchyLoss(e.robust_scale) : nullptr;
    problem.AddResidualBlock(cost, loss, t[e.from].data(), q[e.from].coeffs().data(), t[e.to].data(),
                             q[e.to].coeffs().data());
  }
  for (int i = 0; i < n; ++i) {
    if (!problem.HasParameterBlock(t[i].data())) continue;
    problem.SetManifold(q[i].coeffs().data(), new ceres::EigenQuaternionManifold);  // the problem owns it
  }
  for (int i = 0; i < std::min(n, std::max(1, options.fixed_nodes)); ++i) {
    if (!problem.HasParameterBlock(t[i].data())) continue;
    problem.SetParameterBlockConstant(t[i].data());
    problem.SetParameterBlockConstant(q[i].coeffs().data());
  }
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  solver.max_num_iterations = options.max_iterations;
  solver.num_threads = 1;  // reproducible
  solver.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  std::vector<SE3> out(n);
  for (int i = 0; i < n; ++i) out[i] = poseFromTranslationQuaternion(t[i], q[i].normalized());
  return out;
}

#else  // FLOWFUSION_HAVE_CERES

std::vector<SE3> optimizePoseGraph(const std::vector<SE3>&, const std::vector<PoseGraphEdge>&,
                                   const PoseGraphOptions&) {
  throw InputError("loop closure needs Ceres: install libceres-dev (scripts/install-deps.sh) and rebuild");
}

#endif  // FLOWFUSION_HAVE_CERES

}  // namespace ff

// LmProblem: evaluation of the residual blocks, the robust-loss correction and the
// accumulation of the normal equations block pair by block pair.
#include <algorithm>
#include <cmath>
#include <limits>

#include "lm_solver.h"

namespace mocap {
namespace {

template <int Rows, int Cols>
using RowMajorMap = Eigen::Map<const Eigen::Matrix<double, Rows, Cols, Eigen::RowMajor>>;

// jtj(row, col : S1 x S2) += A^T B for A (m x S1) and B (m x S2), row-major.
template <int M, int S1, int S2>
void AddProduct(const double* a, const double* b, int m, int row, int col, Eigen::MatrixXd* jtj) {
  jtj->block<S1, S2>(row, col).noalias() +=
      RowMajorMap<M, S1>(a, m, S1).transpose() * RowMajorMap<M, S2>(b, m, S2);
}

template <int M>
void AddProductOfSizes(const double* a, const double* b, int m, int s1, int s2, int row, int col,
                       Eigen::MatrixXd* jtj) {
  if (s1 == 3 && s2 == 3) return AddProduct<M, 3, 3>(a, b, m, row, col, jtj);
  if (s1 == 3 && s2 == 6) return AddProduct<M, 3, 6>(a, b, m, row, col, jtj);
  if (s1 == 6 && s2 == 3) return AddProduct<M, 6, 3>(a, b, m, row, col, jtj);
  if (s1 == 6 && s2 == 6) return AddProduct<M, 6, 6>(a, b, m, row, col, jtj);
  using Map = RowMajorMap<Eigen::Dynamic, Eigen::Dynamic>;
  jtj->block(row, col, s1, s2).noalias() += Map(a, m, s1).transpose() * Map(b, m, s2);
}

// The normal equations' products are unrolled for the pose's block sizes (3, the root's 6)
// and residual sizes (2: a keypoint, 3: an IMU term or a 3D point).
void AddBlockProduct(const double* a, const double* b, int m, int s1, int s2, int row, int col,
                     Eigen::MatrixXd* jtj) {
  switch (m) {
    case 2:
      return AddProductOfSizes<2>(a, b, m, s1, s2, row, col, jtj);
    case 3:
      return AddProductOfSizes<3>(a, b, m, s1, s2, row, col, jtj);
    default:
      return AddProductOfSizes<Eigen::Dynamic>(a, b, m, s1, s2, row, col, jtj);
  }
}

double SquaredNorm(const double* r, int m) {
  double s = 0.0;
  for (int k = 0; k < m; ++k) s += r[k] * r[k];
  return s;
}

}  // namespace

LmProblem::LmProblem(int num_parameters) : num_parameters_(num_parameters) {}

int LmProblem::AddResidualBlock(const ceres::CostFunction* cost, const ceres::LossFunction* loss,
                                const std::vector<int>& offsets, const Eigen::MatrixXd* gram) {
  const std::vector<int32_t>& sizes = cost->parameter_block_sizes();
  Block block{cost,
              loss,
              gram,
              cost->num_residuals(),
              static_cast<int>(sizes.size()),
              static_cast<int>(offsets_.size()),
              static_cast<int>(residuals_.size()),
              static_cast<int>(jacobians_.size())};
  int columns = 0;
  for (size_t k = 0; k < sizes.size(); ++k) {
    offsets_.push_back(offsets[k]);
    sizes_.push_back(sizes[k]);
    columns += sizes[k];
  }
  residuals_.resize(residuals_.size() + block.num_residuals);
  jacobians_.resize(jacobians_.size() + block.num_residuals * columns);
  scratch_.resize(std::max<size_t>(scratch_.size(), block.num_residuals));
  parameters_.resize(std::max<size_t>(parameters_.size(), sizes.size()));
  jacobian_blocks_.resize(parameters_.size());
  blocks_.push_back(block);
  rho_.push_back(0.0);
  return static_cast<int>(blocks_.size()) - 1;
}

std::vector<int> LmProblem::offsets(int i) const {
  const Block& b = blocks_[i];
  return std::vector<int>(offsets_.begin() + b.first_parameter_block,
                          offsets_.begin() + b.first_parameter_block + b.num_parameter_blocks);
}

bool LmProblem::EvaluateBlock(const Block& block, const double* x, double* residuals, bool jacobian,
                              double rho[3]) {
  double* next = jacobians_.data() + block.jacobian_start;
  for (int k = 0; k < block.num_parameter_blocks; ++k) {
    parameters_[k] = x + offsets_[block.first_parameter_block + k];
    jacobian_blocks_[k] = next;
    next += block.num_residuals * sizes_[block.first_parameter_block + k];
  }
  if (!block.cost->Evaluate(parameters_.data(), residuals,
                            jacobian ? jacobian_blocks_.data() : nullptr)) {
    return false;
  }
  const double s = SquaredNorm(residuals, block.num_residuals);
  if (block.loss == nullptr) {
    rho[0] = s, rho[1] = 1.0, rho[2] = 0.0;
  } else {
    block.loss->Evaluate(s, rho);
  }
  return std::isfinite(rho[0]);
}

bool LmProblem::Cost(const double* x, double* cost) {
  double sum = 0.0;
  for (const Block& block : blocks_) {
    double rho[3];
    if (!EvaluateBlock(block, x, scratch_.data(), false, rho)) return false;
    sum += rho[0];
  }
  *cost = 0.5 * sum;
  return std::isfinite(*cost);
}

void LmProblem::EvaluateBlockCosts(const double* x) {
  for (size_t i = 0; i < blocks_.size(); ++i) {
    double rho[3];
    const bool ok = EvaluateBlock(blocks_[i], x, scratch_.data(), false, rho);
    rho_[i] = ok ? rho[0] : std::numeric_limits<double>::infinity();
  }
  costs_at_ = Eigen::Map<const Eigen::VectorXd>(x, num_parameters_);
}

bool LmProblem::Linearize(const double* x, double* cost) {
  double sum = 0.0;
  for (size_t i = 0; i < blocks_.size(); ++i) {
    const Block& block = blocks_[i];
    double* r = residuals_.data() + block.residual_start;
    double rho[3];
    if (!EvaluateBlock(block, x, r, true, rho)) return false;
    Correct(block, SquaredNorm(r, block.num_residuals), rho);
    rho_[i] = rho[0];
    sum += rho[0];
  }
  *cost = 0.5 * sum;
  costs_at_ = Eigen::Map<const Eigen::VectorXd>(x, num_parameters_);
  return std::isfinite(*cost);
}

// The robust loss in Gauss-Newton form (Triggs et al., "Bundle adjustment - a modern
// synthesis", 2000, section 4.3). A block's cost is rho(s)/2, s = |r|^2; its gradient
// rho' J^T r and, dropping r's second derivatives, its Hessian J^T (rho' I + 2 rho'' r r^T) J.
// Replacing r and J by
//   r~ = beta r,   J~ = sqrt(rho') (I - alpha P) J,   P = r r^T / s (a projector: P^2 = P)
// makes the block's plain least-squares gradient and Hessian the robust ones when
//   J~^T r~ = beta sqrt(rho') (1 - alpha) J^T r = rho' J^T r
//       =>  beta = sqrt(rho') / (1 - alpha),
//   J~^T J~ = rho' J^T (I - (2 alpha - alpha^2) P) J = J^T (rho' I + 2 rho'' s P) J
//       =>  alpha^2 / 2 - alpha - s rho'' / rho' = 0  =>  alpha = 1 - sqrt(1 + 2 s rho'' / rho')
// (the root below 1). Where rho'' <= 0 (Cauchy everywhere, Huber's linear part) the curvature
// term would make the model lose its positive definiteness (the square root may not even be
// real); there alpha = 0: r and J are both scaled by sqrt(rho'), a reweighted Gauss-Newton
// step whose gradient is still exact. The cost itself is always the exact rho.
void LmProblem::Correct(const Block& block, double s, const double rho[3]) {
  if (block.loss == nullptr) return;
  const int m = block.num_residuals;
  const double sqrt_rho1 = std::sqrt(std::max(rho[1], 0.0));
  double alpha = 0.0, alpha_over_s = 0.0;
  if (s > 0.0 && rho[2] > 0.0 && rho[1] > 0.0) {
    alpha = 1.0 - std::sqrt(1.0 + 2.0 * s * rho[2] / rho[1]);
    alpha_over_s = alpha / s;
  }
  double* r = residuals_.data() + block.residual_start;
  double* jk = jacobians_.data() + block.jacobian_start;
  for (int k = 0; k < block.num_parameter_blocks; ++k) {  // J: one m x size row-major per block
    const int size = sizes_[block.first_parameter_block + k];
    for (int c = 0; c < size; ++c) {
      double rtj = 0.0;  // r^T J[:, c], of the uncorrected J and r
      for (int row = 0; row < m; ++row) rtj += r[row] * jk[row * size + c];
      const double shift = alpha_over_s * rtj;
      for (int row = 0; row < m; ++row)
        jk[row * size + c] = sqrt_rho1 * (jk[row * size + c] - shift * r[row]);
    }
    jk += m * size;
  }
  const double beta = sqrt_rho1 / (1.0 - alpha);
  for (int row = 0; row < m; ++row) r[row] *= beta;
}

void LmProblem::AddBlock(const Block& block, Eigen::MatrixXd* jtj, Eigen::VectorXd* jtr) const {
  const int m = block.num_residuals;
  const int* offsets = offsets_.data() + block.first_parameter_block;
  const int* sizes = sizes_.data() + block.first_parameter_block;
  const double* r = residuals_.data() + block.residual_start;
  const double* j = jacobians_.data() + block.jacobian_start;
  const bool use_gram = block.gram != nullptr && block.loss == nullptr;
  for (int k = 0, start_k = 0, column_k = 0; k < block.num_parameter_blocks; ++k) {
    const double* jk = j + start_k;
    jtr->segment(offsets[k], sizes[k]).noalias() +=
        RowMajorMap<Eigen::Dynamic, Eigen::Dynamic>(jk, m, sizes[k]).transpose() *
        Eigen::Map<const Eigen::VectorXd>(r, m);
    for (int l = k, start_l = start_k, column_l = column_k; l < block.num_parameter_blocks; ++l) {
      // Only the upper triangle: the block pair goes where its row offset is the smaller.
      const bool in_order = offsets[k] <= offsets[l];
      const int a = in_order ? k : l, b = in_order ? l : k;
      if (use_gram) {
        const int ca = in_order ? column_k : column_l, cb = in_order ? column_l : column_k;
        jtj->block(offsets[a], offsets[b], sizes[a], sizes[b]) +=
            block.gram->block(ca, cb, sizes[a], sizes[b]);
      } else {
        const double* ja = in_order ? jk : j + start_l;
        const double* jb = in_order ? j + start_l : jk;
        AddBlockProduct(ja, jb, m, sizes[a], sizes[b], offsets[a], offsets[b], jtj);
      }
      start_l += m * sizes[l];
      column_l += sizes[l];
    }
    start_k += m * sizes[k];
    column_k += sizes[k];
  }
}

void LmProblem::NormalEquations(Eigen::MatrixXd* jtj, Eigen::VectorXd* jtr) const {
  jtj->setZero(num_parameters_, num_parameters_);
  jtr->setZero(num_parameters_);
  for (const Block& block : blocks_) AddBlock(block, jtj, jtr);
}

}  // namespace mocap

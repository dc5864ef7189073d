// LmProblem: the residual blocks' evaluation, the robust-loss correction, each group's
// Jacobian and its J^T J in one product, scattered into the normal equations block by block.
#include <algorithm>
#include <cmath>
#include <limits>

#include "lm_solver.h"

namespace mocap {
namespace {

// to (m x size, column-major, column stride `stride`) = scale * from (m x size, row-major).
template <int M, int Size>
void CopyScaled(const double* from, double scale, int stride, double* to) {
  using From = Eigen::Map<const Eigen::Matrix<double, M, Size, Eigen::RowMajor>>;
  using To = Eigen::Map<Eigen::Matrix<double, M, Size>, 0, Eigen::OuterStride<>>;
  To(to, M, Size, Eigen::OuterStride<>(stride)) = scale * From(from, M, Size);
}

// Unrolled for a keypoint's 2 rows and a 3D term's 3 over the pose's blocks (3, the root's 6).
void CopyScaled(const double* from, int m, int size, double scale, int stride, double* to) {
  if (m == 2 && size == 3) return CopyScaled<2, 3>(from, scale, stride, to);
  if (m == 2 && size == 6) return CopyScaled<2, 6>(from, scale, stride, to);
  if (m == 3 && size == 3) return CopyScaled<3, 3>(from, scale, stride, to);
  if (m == 3 && size == 6) return CopyScaled<3, 6>(from, scale, stride, to);
  using From =
      Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>;
  using To = Eigen::Map<Eigen::MatrixXd, 0, Eigen::OuterStride<>>;
  To(to, m, size, Eigen::OuterStride<>(stride)) = scale * From(from, m, size);
}

// to(row, col : R x C) += from(fr, fc : R x C), or from(fr, fc : C x R)^T.
template <int R, int C>
void AddBlock(const Eigen::MatrixXd& from, int fr, int fc, bool transposed, int row, int col,
              Eigen::MatrixXd* to) {
  if (transposed) {
    to->block<R, C>(row, col) += from.block<C, R>(fr, fc).transpose();
  } else {
    to->block<R, C>(row, col) += from.block<R, C>(fr, fc);
  }
}

// Unrolled for the pose's block sizes.
void AddBlock(const Eigen::MatrixXd& from, int fr, int fc, bool transposed, int rows, int cols,
              int row, int col, Eigen::MatrixXd* to) {
  if (rows == 3 && cols == 3) return AddBlock<3, 3>(from, fr, fc, transposed, row, col, to);
  if (rows == 3 && cols == 6) return AddBlock<3, 6>(from, fr, fc, transposed, row, col, to);
  if (rows == 6 && cols == 3) return AddBlock<6, 3>(from, fr, fc, transposed, row, col, to);
  if (rows == 6 && cols == 6) return AddBlock<6, 6>(from, fr, fc, transposed, row, col, to);
  if (transposed) {
    to->block(row, col, rows, cols) += from.block(fr, fc, cols, rows).transpose();
  } else {
    to->block(row, col, rows, cols) += from.block(fr, fc, rows, cols);
  }
}

void AddSegment(const Eigen::VectorXd& from, int start, int size, int to_start,
                Eigen::VectorXd* to) {
  if (size == 3) {
    to->segment<3>(to_start) += from.segment<3>(start);
  } else {
    to->segment(to_start, size) += from.segment(start, size);
  }
}

double SquaredNorm(const double* r, int m) {
  double s = 0.0;
  for (int k = 0; k < m; ++k) s += r[k] * r[k];
  return s;
}

}  // namespace

LmProblem::LmProblem(int num_parameters)
    : num_parameters_(num_parameters), groups_by_first_offset_(std::max(num_parameters, 1)) {}

int LmProblem::GroupOf(const std::vector<int>& offsets, bool gram) {
  const int n = static_cast<int>(offsets.size());
  std::vector<int>& candidates = groups_by_first_offset_[n > 0 ? offsets[0] : 0];
  for (int g : candidates) {
    const Group& group = groups_[g];
    if (group.num_parameter_blocks == n && group.gram == gram &&
        std::equal(offsets.begin(), offsets.end(),
                   offsets_.begin() + group.first_parameter_block)) {
      return g;
    }
  }
  Group group;
  group.first_parameter_block = static_cast<int>(offsets_.size());
  group.num_parameter_blocks = n;
  group.gram = gram;
  groups_.push_back(group);
  candidates.push_back(static_cast<int>(groups_.size()) - 1);
  return candidates.back();
}

int LmProblem::AddResidualBlock(const ceres::CostFunction* cost, const ceres::LossFunction* loss,
                                const std::vector<int>& offsets, const Eigen::MatrixXd* gram) {
  const std::vector<int32_t>& sizes = cost->parameter_block_sizes();
  if (offsets.size() != sizes.size()) return -1;
  int columns = 0;
  for (size_t k = 0; k < sizes.size(); ++k) {
    if (offsets[k] < 0 || sizes[k] <= 0 || offsets[k] + sizes[k] > num_parameters_) return -1;
    columns += sizes[k];
  }
  if (gram != nullptr && (gram->rows() != columns || gram->cols() != columns)) return -1;
  const bool use_gram = gram != nullptr && loss == nullptr;
  Block block{cost,
              loss,
              cost->num_residuals(),
              static_cast<int>(sizes.size()),
              0,
              GroupOf(offsets, use_gram),
              0};
  block.first_parameter_block = static_cast<int>(offsets_.size());
  Group& group = groups_[block.group];
  block.row = group.rows;
  group.rows += block.num_residuals;
  group.columns = columns;
  offsets_.insert(offsets_.end(), offsets.begin(), offsets.end());
  sizes_.insert(sizes_.end(), sizes.begin(), sizes.end());
  if (use_gram) group.grams.push_back(gram);
  scratch_.resize(std::max<size_t>(scratch_.size(), block.num_residuals));
  block_jacobian_.resize(std::max<size_t>(block_jacobian_.size(), block.num_residuals * columns));
  parameters_.resize(std::max<size_t>(parameters_.size(), sizes.size()));
  jacobian_blocks_.resize(parameters_.size());
  blocks_.push_back(block);
  rho_.push_back(0.0);
  laid_out_ = false;
  return static_cast<int>(blocks_.size()) - 1;
}

void LmProblem::Layout() {
  int residuals = 0, jacobians = 0;
  for (Group& group : groups_) {
    group.residual_start = residuals;
    group.jacobian_start = jacobians;
    residuals += group.rows;
    jacobians += group.rows * group.columns;
  }
  residuals_.resize(residuals);  // (Eigen's resize leaves them uninitialised)
  jacobians_.resize(jacobians);
  laid_out_ = true;
}

std::vector<int> LmProblem::offsets(int i) const {
  const Block& b = blocks_[i];
  return std::vector<int>(offsets_.begin() + b.first_parameter_block,
                          offsets_.begin() + b.first_parameter_block + b.num_parameter_blocks);
}

bool LmProblem::EvaluateBlock(const Block& block, const double* x, double* residuals, bool jacobian,
                              double rho[3]) {
  double* next = block_jacobian_.data();
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
  if (!laid_out_) Layout();
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
  if (!laid_out_) Layout();
  for (size_t i = 0; i < blocks_.size(); ++i) {
    double rho[3];
    const bool ok = EvaluateBlock(blocks_[i], x, scratch_.data(), false, rho);
    rho_[i] = ok ? rho[0] : std::numeric_limits<double>::infinity();
  }
  costs_at_ = Eigen::Map<const Eigen::VectorXd>(x, num_parameters_);
}

bool LmProblem::Linearize(const double* x, double* cost) {
  if (!laid_out_) Layout();
  double sum = 0.0;
  for (size_t i = 0; i < blocks_.size(); ++i) {
    const Block& block = blocks_[i];
    double* r = residuals_.data() + groups_[block.group].residual_start + block.row;
    double rho[3];
    if (!EvaluateBlock(block, x, r, true, rho)) return false;
    Correct(block, SquaredNorm(r, block.num_residuals), rho, r);
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
void LmProblem::Correct(const Block& block, double s, const double rho[3], double* r) {
  const int m = block.num_residuals;
  double scale = 1.0;  // of J, as it is copied to the group's
  if (block.loss != nullptr) {
    const double sqrt_rho1 = std::sqrt(std::max(rho[1], 0.0));
    double alpha = 0.0;
    if (s > 0.0 && rho[2] > 0.0 && rho[1] > 0.0) {
      alpha = 1.0 - std::sqrt(1.0 + 2.0 * s * rho[2] / rho[1]);
      // J <- sqrt(rho') (J - (alpha / s) r (r^T J)), column by column of each block.
      for (int k = 0; k < block.num_parameter_blocks; ++k) {
        const int size = sizes_[block.first_parameter_block + k];
        double* j = jacobian_blocks_[k];  // m x size, row-major
        for (int c = 0; c < size; ++c) {
          double rtj = 0.0;
          for (int row = 0; row < m; ++row) rtj += r[row] * j[row * size + c];
          for (int row = 0; row < m; ++row)
            j[row * size + c] = sqrt_rho1 * (j[row * size + c] - alpha / s * rtj * r[row]);
        }
      }
    } else {
      scale = sqrt_rho1;
    }
    const double beta = sqrt_rho1 / (1.0 - alpha);
    for (int row = 0; row < m; ++row) r[row] *= beta;
  }
  // Into the group's column-major Jacobian, scaled.
  const Group& group = groups_[block.group];
  double* column = jacobians_.data() + group.jacobian_start + block.row;
  for (int k = 0; k < block.num_parameter_blocks; ++k) {
    const int size = sizes_[block.first_parameter_block + k];
    CopyScaled(jacobian_blocks_[k], m, size, scale, group.rows, column);
    column += size * group.rows;
  }
}

void LmProblem::AddGroup(const Group& group, Eigen::MatrixXd* jtj, Eigen::VectorXd* jtr) {
  const Eigen::Map<const Eigen::MatrixXd> j(jacobians_.data() + group.jacobian_start, group.rows,
                                            group.columns);
  const Eigen::Map<const Eigen::VectorXd> r(residuals_.data() + group.residual_start, group.rows);
  gradient_.noalias() = j.transpose() * r;
  if (!group.gram) {  // the lower triangle of the group's J^T J, in one product
    gram_.setZero(group.columns, group.columns);
    gram_.selfadjointView<Eigen::Lower>().rankUpdate(j.transpose());
  }
  const int* offsets = offsets_.data() + group.first_parameter_block;
  const int* sizes = sizes_.data() + group.first_parameter_block;
  for (int k = 0, ck = 0; k < group.num_parameter_blocks; ck += sizes[k], ++k) {
    AddSegment(gradient_, ck, sizes[k], offsets[k], jtr);
    for (int l = k, cl = ck; l < group.num_parameter_blocks; cl += sizes[l], ++l) {
      // Only jtj's upper triangle is kept: the pair goes to (a, b), the smaller offset first.
      const bool in_order = offsets[k] <= offsets[l];
      const int a = in_order ? k : l, b = in_order ? l : k;
      if (group.gram) {
        for (const Eigen::MatrixXd* g : group.grams)
          AddBlock(*g, in_order ? ck : cl, in_order ? cl : ck, false, sizes[a], sizes[b],
                   offsets[a], offsets[b], jtj);
      } else {  // from the lower block (l, k), J_l^T J_k: transposed when k comes first
        AddBlock(gram_, cl, ck, in_order, sizes[a], sizes[b], offsets[a], offsets[b], jtj);
      }
    }
  }
}

void LmProblem::NormalEquations(Eigen::MatrixXd* jtj, Eigen::VectorXd* jtr) {
  jtj->setZero(num_parameters_, num_parameters_);
  jtr->setZero(num_parameters_);
  for (const Group& group : groups_) AddGroup(group, jtj, jtr);
}

}  // namespace mocap

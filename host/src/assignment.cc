#include "mocap/assignment.h"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace mocap {
namespace {

// The Hungarian method on a square matrix: the column of each row in a minimum-cost perfect
// matching. Potentials u (rows) and v (columns); rows added one at a time, each by the
// shortest augmenting path (Dijkstra over reduced costs). 1-based arrays, column 0 the
// row being added.
std::vector<int> SquareAssignment(const Eigen::MatrixXd& a) {
  const int n = static_cast<int>(a.rows());
  const double kInf = std::numeric_limits<double>::infinity();
  std::vector<double> u(n + 1, 0.0), v(n + 1, 0.0);
  std::vector<int> row_of(n + 1, 0), way(n + 1, 0);
  for (int i = 1; i <= n; ++i) {
    row_of[0] = i;
    int j0 = 0;
    std::vector<double> min_to(n + 1, kInf);
    std::vector<bool> used(n + 1, false);
    do {
      used[j0] = true;
      const int i0 = row_of[j0];
      double delta = kInf;
      int j1 = 0;
      for (int j = 1; j <= n; ++j) {
        if (used[j]) continue;
        const double reduced = a(i0 - 1, j - 1) - u[i0] - v[j];
        if (reduced < min_to[j]) min_to[j] = reduced, way[j] = j0;
        if (min_to[j] < delta) delta = min_to[j], j1 = j;
      }
      for (int j = 0; j <= n; ++j) {
        if (used[j]) {
          u[row_of[j]] += delta, v[j] -= delta;
        } else {
          min_to[j] -= delta;
        }
      }
      j0 = j1;
    } while (row_of[j0] != 0);
    do {
      const int j1 = way[j0];
      row_of[j0] = row_of[j1];
      j0 = j1;
    } while (j0);
  }
  std::vector<int> column_of(n, -1);
  for (int j = 1; j <= n; ++j) column_of[row_of[j] - 1] = j - 1;
  return column_of;
}

}  // namespace

std::vector<int> AssignRows(const Eigen::MatrixXd& cost, double gate) {
  if (!std::isfinite(gate) || gate < 0)
    throw std::invalid_argument("AssignRows: the gate must be finite and >= 0");
  const int rows = static_cast<int>(cost.rows()), cols = static_cast<int>(cost.cols());
  // Rows + columns square: a row pairs with a column, or with its own "alone" column at
  // gate / 2; a column likewise with its own "alone" row; the alone rows and columns pair
  // among themselves for nothing. A pair above the gate (or never made) costs more than
  // leaving both alone, so it is never chosen: it costs more than any whole matching without it.
  const int n = rows + cols;
  const double never = (gate + 1.0) * (n + 1);
  Eigen::MatrixXd square = Eigen::MatrixXd::Constant(n, n, never);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const double x = cost(r, c);
      square(r, c) = std::isfinite(x) && x <= gate ? x : never;
    }
    square(r, cols + r) = 0.5 * gate;
  }
  for (int c = 0; c < cols; ++c) square(rows + c, c) = 0.5 * gate;
  square.bottomRightCorner(cols, rows).setZero();
  std::vector<int> column_of = SquareAssignment(square), out(rows, -1);
  for (int r = 0; r < rows; ++r)
    if (column_of[r] < cols && square(r, column_of[r]) < never) out[r] = column_of[r];
  return out;
}

}  // namespace mocap

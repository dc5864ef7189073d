// The gated assignment: the cheapest pairing of persons and subjects, no pair above the gate,
// against every pairing enumerated on small random matrices.
#include "mocap/assignment.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>

namespace mocap {
namespace {

// The cost of an assignment as AssignRows defines it: pairs made, plus gate / 2 per row and
// per column left alone.
double Total(const Eigen::MatrixXd& cost, const std::vector<int>& column_of, double gate) {
  double total = 0;
  std::vector<bool> taken(cost.cols(), false);
  for (int r = 0; r < cost.rows(); ++r) {
    if (column_of[r] < 0) {
      total += 0.5 * gate;
      continue;
    }
    EXPECT_FALSE(taken[column_of[r]]) << "column " << column_of[r] << " used twice";
    taken[column_of[r]] = true;
    EXPECT_TRUE(std::isfinite(cost(r, column_of[r])) && cost(r, column_of[r]) <= gate);
    total += cost(r, column_of[r]);
  }
  return total + 0.5 * gate * std::count(taken.begin(), taken.end(), false);
}

// The cheapest total over every assignment (rows in turn take a free column or none).
double Cheapest(const Eigen::MatrixXd& cost, double gate) {
  std::vector<int> column_of(cost.rows(), -1);
  std::vector<bool> taken(cost.cols(), false);
  double best = INFINITY;
  std::function<void(int)> visit = [&](int r) {
    if (r == cost.rows()) {
      best = std::min(best, Total(cost, column_of, gate));
      return;
    }
    column_of[r] = -1;
    visit(r + 1);
    for (int c = 0; c < cost.cols(); ++c) {
      if (taken[c] || !std::isfinite(cost(r, c)) || cost(r, c) > gate) continue;
      taken[c] = true, column_of[r] = c;
      visit(r + 1);
      taken[c] = false, column_of[r] = -1;
    }
  };
  visit(0);
  return best;
}

TEST(AssignRows, TheCheapestPairingWinsOverTheGreedyOne) {
  Eigen::MatrixXd cost(2, 2);
  cost << 1.0, 2.0,  //
      2.0, 10.0;     // greedy takes (0,0) at 1 and leaves row 1 with 10
  EXPECT_EQ(AssignRows(cost, 20.0), (std::vector<int>{1, 0}));
}

TEST(AssignRows, NoPairAboveTheGateAndNoneThatIsNotFinite) {
  Eigen::MatrixXd cost(3, 2);
  cost << 0.5, NAN,  //
      7.0, 6.0,      //
      INFINITY, 0.2;
  EXPECT_EQ(AssignRows(cost, 5.0), (std::vector<int>{0, -1, 1}));
  EXPECT_EQ(AssignRows(cost, 0.1), (std::vector<int>{-1, -1, -1}));
  EXPECT_EQ(AssignRows(Eigen::MatrixXd(0, 3), 1.0), std::vector<int>{});
  EXPECT_EQ(AssignRows(Eigen::MatrixXd(2, 0), 1.0), (std::vector<int>{-1, -1}));
  EXPECT_THROW(AssignRows(cost, NAN), std::invalid_argument);
  EXPECT_THROW(AssignRows(cost, -1.0), std::invalid_argument);
}

TEST(AssignRows, MatchesEveryPairingEnumeratedOnRandomMatrices) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> uniform(0.0, 10.0);
  for (int trial = 0; trial < 300; ++trial) {
    const int rows = 1 + trial % 6, cols = 1 + (trial / 6) % 6;
    Eigen::MatrixXd cost(rows, cols);
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < cols; ++c) cost(r, c) = uniform(rng) < 1.0 ? INFINITY : uniform(rng);
    const double gate = uniform(rng);
    const std::vector<int> got = AssignRows(cost, gate);
    ASSERT_EQ(static_cast<int>(got.size()), rows);
    EXPECT_NEAR(Total(cost, got, gate), Cheapest(cost, gate), 1e-9) << "trial " << trial;
  }
}

}  // namespace
}  // namespace mocap

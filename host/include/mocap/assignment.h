// A minimum-cost one-to-one assignment with a gate: which detected person is which tracked
// subject (rows: persons, columns: subjects), each row and each column used at most once, a
// pair whose cost exceeds the gate never made. Kuhn-Munkres (the Hungarian method with
// potentials), O(n^3) in rows + columns: a camera's few people and the stage's few subjects.
#ifndef MOCAP_ASSIGNMENT_H_
#define MOCAP_ASSIGNMENT_H_

#include <Eigen/Core>
#include <vector>

namespace mocap {

// The column assigned to each row of `cost`, -1 for none, minimising the sum over the pairs
// made plus gate / 2 for every row and every column left alone: a pair is made only where it
// costs at most the gate, and among such pairings the cheapest total wins. Costs that are not
// finite (NaN, infinite) are pairs never made. gate must be finite and non-negative.
std::vector<int> AssignRows(const Eigen::MatrixXd& cost, double gate);

}  // namespace mocap

#endif  // MOCAP_ASSIGNMENT_H_

// The options structs: VisitFields names every member (so everything derived from it, the
// session reader and the bindings, has every field), and IsValid says which conditions fail.
#include <gtest/gtest.h>

#include <functional>
#include <utility>

#include "mocap/solver_options.h"
#include "mocap/stream_sync.h"
#include "mocap/window_calibration.h"

namespace mocap {
namespace {

// Counts an aggregate's members: T{AnyField{}...} is well-formed for up to as many
// initialisers as T has members, since AnyField converts to any member type.
struct AnyField {
  template <typename T>
  operator T() const;
};
template <typename T, typename... A>
constexpr auto Constructible(int) -> decltype(T{std::declval<A>()...}, true) {
  return true;
}
template <typename T, typename... A>
constexpr bool Constructible(...) {
  return false;
}
template <typename T, typename... A>
constexpr size_t CountMembers() {
  if constexpr (Constructible<T, A..., AnyField>(0))
    return CountMembers<T, A..., AnyField>();
  else
    return sizeof...(A);
}

template <typename T>
size_t CountVisited() {
  size_t n = 0;
  T::VisitFields([&](const char*, auto) { n++; });
  return n;
}

TEST(Options, VisitFieldsNamesEveryMember) {
  EXPECT_EQ(CountVisited<TermOptions>(), CountMembers<TermOptions>());
  EXPECT_EQ(CountVisited<SolverOptions>(), CountMembers<SolverOptions>());
  EXPECT_EQ(CountVisited<HeldPose>(), CountMembers<HeldPose>());
  EXPECT_EQ(CountVisited<CalibrationOptions>(), CountMembers<CalibrationOptions>());
  EXPECT_EQ(CountVisited<SyncOptions>(), CountMembers<SyncOptions>());
  // The counting itself: a struct of three members counts three.
  struct Three {
    int a = 0;
    double b = 0;
    TermOptions c;
  };
  EXPECT_EQ(CountMembers<Three>(), 3u);
}

TEST(Options, TheDefaultsAreValid) {
  std::string error;
  EXPECT_TRUE(SolverOptions().IsValid(&error)) << error;
  EXPECT_TRUE(CalibrationOptions().IsValid(&error)) << error;
}

// Each case breaks one condition; the message names that field and no other.
template <typename Options>
void ExpectOneMessageEach(
    const std::vector<std::pair<std::string, std::function<void(Options*)>>>& cases) {
  for (const auto& [field, breaks] : cases) {
    Options o;
    breaks(&o);
    std::string error;
    EXPECT_FALSE(o.IsValid(&error)) << field;
    EXPECT_EQ(error.rfind(field + " ", 0), 0u) << field << ": " << error;
    EXPECT_NE(error.find("out of range"), std::string::npos) << error;
    EXPECT_EQ(error.find(';'), std::string::npos) << "one condition, one message: " << error;
  }
}

TEST(Options, EachFailingSolverConditionHasItsOwnMessage) {
  ExpectOneMessageEach<SolverOptions>({
      {"position.weight", [](SolverOptions* o) { o->position.weight = -1; }},
      {"orientation.loss_scale", [](SolverOptions* o) { o->orientation.loss_scale = 0; }},
      {"pca_deviation.weight", [](SolverOptions* o) { o->pca_deviation.weight = NAN; }},
      {"accel_at_rest", [](SolverOptions* o) { o->accel_at_rest.x() = INFINITY; }},
      {"min_confidence", [](SolverOptions* o) { o->min_confidence = 1; }},
      {"max_quaternion_error", [](SolverOptions* o) { o->max_quaternion_error = 0; }},
      {"max_history_gap", [](SolverOptions* o) { o->max_history_gap = -0.1; }},
      {"velocity_gain", [](SolverOptions* o) { o->velocity_gain = 0; }},
      {"velocity_gain", [](SolverOptions* o) { o->velocity_gain = 1.5; }},
      {"motion_velocity_gain", [](SolverOptions* o) { o->motion_velocity_gain = 0; }},
      {"motion.weight", [](SolverOptions* o) { o->motion.weight = -1; }},
      {"ground.loss_scale", [](SolverOptions* o) { o->ground.loss_scale = 0; }},
      {"floor_height", [](SolverOptions* o) { o->floor_height = -INFINITY; }},
      {"ground_unobserved_scale", [](SolverOptions* o) { o->ground_unobserved_scale = 0.5; }},
      {"video_only_position_loss_scale",
       [](SolverOptions* o) { o->video_only_position_loss_scale = 0.5; }},
      {"video_only_motion_weight_scale",
       [](SolverOptions* o) { o->video_only_motion_weight_scale = 0; }},
      {"prediction_slack", [](SolverOptions* o) { o->prediction_slack = -0.5; }},
      {"max_keypoint_cost", [](SolverOptions* o) { o->max_keypoint_cost = 0; }},
      {"heading_time_constant", [](SolverOptions* o) { o->heading_time_constant = INFINITY; }},
      {"max_heading_step", [](SolverOptions* o) { o->max_heading_step = 4; }},
      {"heading_baseline_s", [](SolverOptions* o) { o->heading_baseline_s = -1; }},
      {"slip_keypoint_cost", [](SolverOptions* o) { o->slip_keypoint_cost = -1; }},
      {"slip_window_s", [](SolverOptions* o) { o->slip_window_s = 0; }},
      {"slip_readmit_deg", [](SolverOptions* o) { o->slip_readmit_deg = 200; }},
      {"slip_readmit_s", [](SolverOptions* o) { o->slip_readmit_s = NAN; }},
      {"max_iterations", [](SolverOptions* o) { o->max_iterations = 0; }},
      {"max_initial_iterations", [](SolverOptions* o) { o->max_initial_iterations = 0; }},
      {"function_tolerance", [](SolverOptions* o) { o->function_tolerance = -1; }},
      {"gradient_tolerance", [](SolverOptions* o) { o->gradient_tolerance = NAN; }},
      {"parameter_tolerance", [](SolverOptions* o) { o->parameter_tolerance = -1; }},
  });
}

TEST(Options, EachFailingCalibrationConditionHasItsOwnMessage) {
  ExpectOneMessageEach<CalibrationOptions>({
      {"terms: velocity_gain", [](CalibrationOptions* o) { o->terms.velocity_gain = 2; }},
      {"scale_sigma", [](CalibrationOptions* o) { o->scale_sigma = 0; }},
      {"shift_sigma", [](CalibrationOptions* o) { o->shift_sigma = -1; }},
      {"shift_sigmas",
       [](CalibrationOptions* o) {
         o->shift_sigmas = {{1, 0, 1}};
       }},
      {"joint_sigmas",
       [](CalibrationOptions* o) {
         o->joint_sigmas = {{0, NAN, 0}};
       }},
      {"held_poses.frame",
       [](CalibrationOptions* o) {
         o->held_poses = {{-1, Eigen::VectorXd::Zero(66), 0.05}};
       }},
      {"held_poses.sigma",
       [](CalibrationOptions* o) {
         o->held_poses = {{0, Eigen::VectorXd::Zero(66), 0}};
       }},
      {"heading_priors",
       [](CalibrationOptions* o) {
         o->heading_priors = {{NAN, 0.1}};
       }},
      {"site_sigma", [](CalibrationOptions* o) { o->site_sigma = 0; }},
      {"site_observable_std", [](CalibrationOptions* o) { o->site_observable_std = -1; }},
      {"max_iterations", [](CalibrationOptions* o) { o->max_iterations = 0; }},
      {"num_threads", [](CalibrationOptions* o) { o->num_threads = 0; }},
  });
}

TEST(Options, EveryFailingConditionIsListed) {
  SolverOptions o;
  o.velocity_gain = 0, o.max_iterations = 0, o.position.loss_scale = -1;
  std::string error;
  ASSERT_FALSE(o.IsValid(&error));
  EXPECT_EQ(error,
            "position.loss_scale = -1 is out of range (must be finite and > 0); "
            "velocity_gain = 0 is out of range (must be in (0, 1]); "
            "max_iterations = 0 is out of range (must be >= 1)");
}

}  // namespace
}  // namespace mocap

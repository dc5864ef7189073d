#include "mocap/solver_options.h"

#include <cmath>
#include <type_traits>

#include "option_checks.h"

namespace mocap {

bool TermOptions::IsValid(const std::string& name, std::string* error) const {
  internal::OptionChecks check(name + ".");
  check.Expect(std::isfinite(weight) && weight >= 0.0, "weight", weight, "finite and >= 0");
  check.Expect(std::isfinite(loss_scale) && loss_scale > 0.0, "loss_scale", loss_scale,
               "finite and > 0");
  check.Expect(loss == LossType::kTrivial || loss == LossType::kCauchy || loss == LossType::kHuber,
               "loss", "trivial, cauchy or huber");
  return check.Done(error);
}

bool SolverOptions::IsValid(std::string* error) const {
  internal::OptionChecks check;
  VisitFields([&](const char* name, auto member) {
    if constexpr (std::is_same_v<decltype(member), TermOptions SolverOptions::*>) {
      std::string messages;
      const bool valid = (this->*member).IsValid(name, &messages);
      check.Nested(valid, messages);
    }
  });
  check.Expect(accel_at_rest.allFinite(), "accel_at_rest", "finite");
  check.Expect(!std::isinf(floor_height), "floor_height", floor_height, "finite, or NaN: unknown");
  check.Expect(
      video_only_position_loss_scale >= 1.0 && std::isfinite(video_only_position_loss_scale),
      "video_only_position_loss_scale", video_only_position_loss_scale, "finite and >= 1");
  check.Expect(
      video_only_motion_weight_scale > 0.0 && std::isfinite(video_only_motion_weight_scale),
      "video_only_motion_weight_scale", video_only_motion_weight_scale, "finite and > 0");
  check.Expect(ground_unobserved_scale >= 1.0 && std::isfinite(ground_unobserved_scale),
               "ground_unobserved_scale", ground_unobserved_scale, "finite and >= 1");
  check.Expect(min_confidence >= 0.0 && min_confidence < 1.0, "min_confidence", min_confidence,
               "in [0, 1)");
  check.Expect(max_quaternion_error > 0.0, "max_quaternion_error", max_quaternion_error, "> 0");
  check.Expect(max_history_gap > 0.0, "max_history_gap", max_history_gap, "> 0 s");
  check.Expect(velocity_gain > 0.0 && velocity_gain <= 1.0, "velocity_gain", velocity_gain,
               "in (0, 1]");
  check.Expect(motion_velocity_gain > 0.0 && motion_velocity_gain <= 1.0, "motion_velocity_gain",
               motion_velocity_gain, "in (0, 1]");
  check.Expect(prediction_slack >= 0.0 && std::isfinite(prediction_slack), "prediction_slack",
               prediction_slack, "finite and >= 0");
  check.Expect(max_keypoint_cost > 0.0, "max_keypoint_cost", max_keypoint_cost, "> 0");
  check.Expect(heading_time_constant >= 0.0 && std::isfinite(heading_time_constant),
               "heading_time_constant", heading_time_constant, "finite and >= 0 s");
  check.Expect(max_heading_step > 0.0 && max_heading_step <= M_PI, "max_heading_step",
               max_heading_step, "in (0, pi] rad");
  check.Expect(heading_baseline_s >= 0.0 && std::isfinite(heading_baseline_s), "heading_baseline_s",
               heading_baseline_s, "finite and >= 0 s");
  check.Expect(slip_keypoint_cost >= 0.0 && std::isfinite(slip_keypoint_cost), "slip_keypoint_cost",
               slip_keypoint_cost, "finite and >= 0");
  check.Expect(slip_window_s > 0.0 && std::isfinite(slip_window_s), "slip_window_s", slip_window_s,
               "finite and > 0 s");
  check.Expect(slip_readmit_deg > 0.0 && slip_readmit_deg <= 180.0, "slip_readmit_deg",
               slip_readmit_deg, "in (0, 180] degrees");
  check.Expect(slip_readmit_s >= 0.0 && std::isfinite(slip_readmit_s), "slip_readmit_s",
               slip_readmit_s, "finite and >= 0 s");
  check.Expect(max_iterations >= 1, "max_iterations", max_iterations, ">= 1");
  check.Expect(max_initial_iterations >= 1, "max_initial_iterations", max_initial_iterations,
               ">= 1");
  check.Expect(function_tolerance >= 0.0, "function_tolerance", function_tolerance, ">= 0");
  check.Expect(gradient_tolerance >= 0.0, "gradient_tolerance", gradient_tolerance, ">= 0");
  check.Expect(parameter_tolerance >= 0.0, "parameter_tolerance", parameter_tolerance, ">= 0");
  return check.Done(error);
}

}  // namespace mocap

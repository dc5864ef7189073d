"""Evaluation: accuracy metrics, the baselines users would pick instead, the solver on
simulated takes of real motion (`mocap eval`), the paper's tables, the real Balancing trial
(`mocap eval-edge`, the edge detector's PCK), the solver benchmark and the comparison with
Pose2Sim's triangulation on that trial (`peer`)."""

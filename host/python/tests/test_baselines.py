import numpy as np

from mocap import _core, paths
from mocap.eval import baselines
from mocap.model import studio, triangulation
from mocap.sim import detector


def _scene():
    skeleton = _core.Skeleton.load(str(paths.DEFAULT_SKELETON))
    layout = _core.KeypointLayout.load(str(paths.LAYOUTS / "coco17.json"), skeleton)
    theta = np.zeros(skeleton.pose_dim)
    theta[:3] = [0.2, -0.1, 0.95]
    theta[3:6] = [0, 0, 0.6]
    theta[6:] = np.random.default_rng(0).uniform(-0.2, 0.2, 60)
    points = studio.site_positions(skeleton, layout.bones, layout.offsets, theta)
    return skeleton, layout, theta, points


def test_triangulation_is_exact_on_exact_detections_and_drops_an_outlier_view():
    _, _, _, points = _scene()
    rig = studio.ring_rig(5)
    det = studio.keypoints(rig, points)
    det[2, 0, :2] += 300.0  # one camera's nose is far off
    got, valid = triangulation.triangulate(rig, det, triangulation.TriangulationSettings())
    assert valid.all()
    np.testing.assert_allclose(got, points, atol=1e-6)


def test_a_mirrored_camera_is_swapped_back():
    _, layout, _, points = _scene()
    rig = studio.ring_rig(5)
    det = studio.keypoints(rig, points)
    twins = detector.mirror(layout.names)
    swapped = det.copy()
    swapped[1] = det[1, twins]
    s = triangulation.TriangulationSettings()
    got, valid = triangulation.triangulate(rig, swapped, s)
    fixed = baselines.fix_swaps(rig, swapped, got, valid, twins, s)
    np.testing.assert_allclose(fixed, det)


def test_one_euro_filter_settles_and_holds_missing_values():
    f = baselines.OneEuro(triangulation.TriangulationSettings())
    for i in range(200):
        out = f(i / 60, np.array([[1.0, 2.0, 3.0]]))
    np.testing.assert_allclose(out, [[1.0, 2.0, 3.0]], atol=1e-6)
    np.testing.assert_allclose(f(200 / 60, np.array([[np.nan] * 3])), [[1.0, 2.0, 3.0]], atol=1e-6)


def test_fit_to_points_recovers_the_sites():
    skeleton, layout, theta, points = _scene()
    start = theta.copy()
    start[:3] += [0.05, 0.05, 0.0]
    start[6:] += 0.1
    ok, fitted = _core.fit_to_points(skeleton, layout.bones, layout.offsets, points, np.ones(len(layout)), start, 50)
    assert ok
    np.testing.assert_allclose(studio.site_positions(skeleton, layout.bones, layout.offsets, fitted), points, atol=1e-4)


def test_triangulation_baseline_in_the_evaluation(shared):
    from mocap.eval import simulated as evaluation
    from mocap.sim import take

    config = take.Config(preset="hq13")
    fused = evaluation.evaluate(shared / "data/mocap/cmu-daz/16_36.bvh", config, [], 0)
    video = evaluation.evaluate(shared / "data/mocap/cmu-daz/16_36.bvh", config, [], 0, baseline="triangulation")
    assert video["method"] == "triangulation" and video["pos_error_cm"] < 8.0
    assert fused["ori_error_deg"] < video["ori_error_deg"]  # axial rotation comes from the IMUs

"""Model-independent parts of detection: anchors, decoders, non-maximum suppression,
rotated regions and crops."""

import numpy as np
import pytest

from mocap_edge.detect import anchors, decoders, roi


def test_blazepose_anchors_follow_mediapipes_layout():
    a = anchors.ssd_anchors()
    assert a.shape == (2254, 2)
    np.testing.assert_allclose(a[0], a[1])  # two anchors per cell at stride 8
    np.testing.assert_allclose(a[0], [0.5 / 28, 0.5 / 28])
    np.testing.assert_allclose(a[2], [1.5 / 28, 0.5 / 28])  # row-major cells
    np.testing.assert_allclose(a[1568], [0.5 / 14, 0.5 / 14])  # stride 16 starts after 28 x 28 x 2
    np.testing.assert_allclose(a[1960:1966], np.repeat([[0.5 / 7, 0.5 / 7]], 6, axis=0))  # strides 32 merged
    np.testing.assert_allclose(a[-1], [6.5 / 7, 6.5 / 7])


def test_ssd_decoding_puts_boxes_and_keypoints_at_their_anchor_offsets():
    a = anchors.ssd_anchors()
    raw = np.zeros((len(a), 12))
    scores = np.full(len(a), -10.0)
    raw[100] = [3, -2, 40, 80, 1, 2, 5, -30, 0, 0, 0, 0]
    scores[100] = 2.0
    scores[200] = -0.1  # below 0.5 after the sigmoid
    found = decoders.decode_ssd(raw, scores, a, 224)
    assert len(found) == 1
    c = a[100] * 224
    np.testing.assert_allclose(found[0].box, [c[0] + 3 - 20, c[1] - 2 - 40, c[0] + 3 + 20, c[1] - 2 + 40])
    np.testing.assert_allclose(found[0].keypoints[:2], [c + [1, 2], c + [5, -30]])
    assert found[0].score == pytest.approx(1 / (1 + np.exp(-2)))


def test_weighted_nms_merges_overlapping_detections_and_keeps_separate_ones():
    def det(x, score):
        return decoders.Detection(np.array([x, 0, x + 10, 10.0]), np.array([[x, 0.0]]), score)

    out = decoders.weighted_nms([det(0, 0.9), det(1, 0.3), det(50, 0.8)])
    assert len(out) == 2
    np.testing.assert_allclose(out[0].box[0], (0 * 0.9 + 1 * 0.3) / 1.2)
    assert out[0].score == 0.9 and out[1].box[0] == 50


def test_rotated_region_maps_points_both_ways_and_crops_where_it_says():
    image = np.zeros((480, 640, 3), np.uint8)
    dot = np.array([400.5, 150.5])  # a pixel centre
    image[150, 400] = 255
    region = roi.aligned(centre=np.array([350.0, 250.0]), towards=np.array([380.0, 120.0]))
    points = np.array([[10.0, 20.0], [200.0, 3.5]])
    np.testing.assert_allclose(region.to_image(region.to_crop(points, 256), 256), points)
    crop = region.crop(image, 256).astype(float).sum(axis=2)
    ys, xs = np.nonzero(crop)
    centroid = np.array([np.average(xs, weights=crop[ys, xs]), np.average(ys, weights=crop[ys, xs])]) + 0.5
    np.testing.assert_allclose(centroid, region.to_crop(dot[None], 256)[0], atol=0.5)
    # `towards` is straight up in the crop, at 1 / (2 x 1.25) of the side above the centre.
    np.testing.assert_allclose(region.to_crop(np.array([[380.0, 120.0]]), 256)[0], [128, 128 - 256 / 2.5], atol=1e-9)


def test_letterbox_keeps_the_aspect_ratio():
    box = roi.letterbox(640, 480)
    np.testing.assert_allclose(box.to_crop(np.array([[0.0, 0.0], [640.0, 480.0]]), 224),
                               [[0, 224 * 80 / 640], [224, 224 * 560 / 640]])


def test_heatmap_simcc_and_regression_decoders():
    h, w = 64, 48
    yy, xx = np.mgrid[0:h, 0:w]
    peaks = np.array([[10.3, 20.0], [30.0, 50.2]])  # heatmap cells (x, y)
    maps = np.stack([np.exp(-((xx - px) ** 2 + (yy - py) ** 2) / 4.0) for px, py in peaks])
    kp = decoders.decode_heatmaps(maps, (192, 256))  # input 4x the heatmap
    np.testing.assert_allclose(kp[:, :2], (peaks + 0.5) * 4 - 0.5, atol=1.1)
    assert np.all(kp[:, 2] > 0.9)
    sx, sy = np.zeros((2, 384)), np.zeros((2, 512))
    sx[0, 100], sy[0, 300], sx[1, 7], sy[1, 9] = 0.9, 0.8, 0.5, 0.6
    np.testing.assert_allclose(decoders.decode_simcc(sx, sy), [[50, 150, 0.8], [3.5, 4.5, 0.5]])
    raw = np.array([[12.0, 34.0, 0.0, 0.0, 100.0], [1.0, 2.0, 0.0, -100.0, 100.0]]).reshape(-1)
    np.testing.assert_allclose(decoders.decode_regression(raw, 2), [[12, 34, 0.5], [1, 2, 0]], atol=1e-12)


def test_tiles_cover_the_long_side_in_half_overlapping_squares():
    from mocap_edge.detect.blazepose import tiles

    portrait = tiles(1088, 1920)
    assert [t.size for t in portrait] == [1088.0] * 3
    np.testing.assert_allclose([t.centre for t in portrait], [[544, 544], [544, 960], [544, 1376]])
    landscape = tiles(1920, 1080)
    np.testing.assert_allclose([t.centre for t in landscape], [[540, 540], [960, 540], [1380, 540]])
    assert tiles(640, 640) == [] and tiles(640, 700) == []  # nearly square: the whole image suffices

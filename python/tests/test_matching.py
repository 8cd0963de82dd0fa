"""Features and matching through the bindings equal the C++ pipeline (python_reference.cc) on the
TUM pair and a synthetic pair; guided matches agree with the exact synthetic ground truth."""

import os

import cv2
import numpy as np
import pytest

import imumatch
from conftest import cpp_reference, data_dir


def run_pipeline(camera, motion, gray_a, gray_b, depth_a, detector):
    kps_a, desc_a = imumatch.extract_features(gray_a, detector, 1000)
    kps_b, desc_b = imumatch.extract_features(gray_b, detector, 1000)
    guided = imumatch.match_guided(camera, motion, kps_a, desc_a, kps_b, desc_b, depth_a=depth_a,
                                   image_a=gray_a, image_b=gray_b)
    return kps_a, desc_a, kps_b, desc_b, guided


def assert_matches_equal(result, expected):
    got = np.column_stack([result.query_idx, result.train_idx]).astype(int)
    want = np.array([m[:2] for m in expected], dtype=int).reshape(-1, 2)
    assert got.shape == want.shape
    assert (got == want).all()
    assert np.allclose(result.distance, [m[2] for m in expected], rtol=1e-6)


def compare_with_reference(ref, kps_a, desc_a, kps_b, desc_b, guided):
    assert np.allclose(kps_a, np.array(ref["keypoints_a"]), rtol=1e-6, atol=1e-6)
    assert np.allclose(kps_b, np.array(ref["keypoints_b"]), rtol=1e-6, atol=1e-6)
    assert_matches_equal(guided, ref["guided"])
    refined = np.array([m[3:5] for m in ref["guided"]], dtype=float)
    assert np.allclose(guided.refined_uv_b, refined, atol=1e-5, equal_nan=True)
    assert guided.outcomes == ref["outcomes"]
    assert np.allclose(guided.predictions.uv, np.array(ref["predicted_uv"], dtype=float),
                       atol=1e-4, equal_nan=True)
    assert_matches_equal(imumatch.match_opencv_knn_ratio(desc_a, desc_b, 0.8), ref["bf_opencv"])
    assert_matches_equal(imumatch.match_brute_force(desc_a, desc_b, 0.8), ref["bf_own"])


def tum_pair():
    d = os.path.join(data_dir(), "tum_fr1_xyz_pair")
    gray_a = cv2.imread(os.path.join(d, "img_prev.png"), cv2.IMREAD_GRAYSCALE)
    gray_b = cv2.imread(os.path.join(d, "img_curr.png"), cv2.IMREAD_GRAYSCALE)
    depth_a = cv2.imread(os.path.join(d, "dep_prev.png"), cv2.IMREAD_UNCHANGED)
    motion = imumatch.camera_motion_from_poses(
        0, imumatch.read_tum_pose(os.path.join(d, "pose_prev.txt")),
        1, imumatch.read_tum_pose(os.path.join(d, "pose_curr.txt")))
    return d, gray_a, gray_b, depth_a, motion


def test_tum_pair_equals_cpp():
    d, gray_a, gray_b, depth_a, motion = tum_pair()
    ref = cpp_reference("tum", d)
    out = run_pipeline(imumatch.PinholeCamera.tum_freiburg1(), motion, gray_a, gray_b, depth_a,
                       "orb")
    assert len(out[4]) > 300
    compare_with_reference(ref, *out)


def test_cv2_keypoints_give_the_same_matches():
    _, gray_a, gray_b, depth_a, motion = tum_pair()
    cam = imumatch.PinholeCamera.tum_freiburg1()
    kps_a, desc_a = imumatch.extract_features(gray_a, "orb")
    kps_b, desc_b = imumatch.extract_features(gray_b, "orb")
    as_cv2 = imumatch.to_cv2_keypoints(kps_a)
    assert isinstance(as_cv2[0], cv2.KeyPoint)
    assert np.allclose(imumatch.from_cv2_keypoints(as_cv2), kps_a, atol=1e-4)
    r1 = imumatch.match_guided(cam, motion, kps_a, desc_a, kps_b, desc_b, depth_a=depth_a)
    r2 = imumatch.match_guided(cam, motion, as_cv2, desc_a, imumatch.to_cv2_keypoints(kps_b),
                               desc_b, depth_a=depth_a)
    assert (r1.query_idx == r2.query_idx).all() and (r1.train_idx == r2.train_idx).all()
    dm = imumatch.to_cv2_matches(r1)
    assert dm[0].queryIdx == r1.query_idx[0] and dm[0].trainIdx == r1.train_idx[0]
    # Outcomes account for every query.
    assert len(r1.outcomes) == len(kps_a)
    assert r1.stats["matched"] == len(r1) == r1.outcomes.count("matched")


def synthetic_pair():
    seq = imumatch.make_synthetic_sequence("front1m", frame_times_s=[1.0, 1.1])
    fa, fb = seq.frames
    state = imumatch.ImuStateAtFrame(fa.world_from_imu, fa.imu_velocity_in_world,
                                     seq.imu_initial_bias)
    motion = imumatch.compute_camera_motion(seq.imu, fa.t_ns, fb.t_ns, state, seq.imu_params,
                                            seq.cam_from_imu)
    gray_a = cv2.cvtColor(fa.rgb, cv2.COLOR_BGR2GRAY)
    gray_b = cv2.cvtColor(fb.rgb, cv2.COLOR_BGR2GRAY)
    return seq, motion, gray_a, gray_b


def test_synthetic_pair_equals_cpp_and_the_exact_ground_truth():
    seq, motion, gray_a, gray_b = synthetic_pair()
    ref = cpp_reference("synthetic")
    r = np.array(ref["motion"])
    assert np.allclose(motion.cam_b_from_cam_a.quaternion_wxyz, r[:4], atol=1e-12)
    assert np.allclose(motion.cam_b_from_cam_a.translation, r[4:], atol=1e-12)
    fa, fb = seq.frames
    kps_a, desc_a, kps_b, desc_b, guided = run_pipeline(seq.camera, motion, gray_a, gray_b,
                                                        fa.depth, "sift")
    compare_with_reference(ref, kps_a, desc_a, kps_b, desc_b, guided)
    # Independent truth: A's keypoints moved by the exact poses and the rendered depth.
    gt = imumatch.camera_motion_from_poses(fa.t_ns, fa.world_from_cam, fb.t_ns, fb.world_from_cam)
    q, t = guided.query_idx, guided.train_idx
    uv_a = kps_a[q, :2]
    z = fa.depth[np.round(uv_a[:, 1]).astype(int), np.round(uv_a[:, 0]).astype(int)] / 5000.0
    ok = z > 0
    p_b = gt.cam_b_from_cam_a.transform(seq.camera.unproject(uv_a[ok], z[ok]))
    err = np.linalg.norm(seq.camera.project(p_b) - guided.refined_uv_b[ok], axis=1)
    assert ok.sum() > 200
    assert np.mean(err < 1.5) > 0.95


def test_feature_kinds_and_zero_copy_descriptors():
    seq = imumatch.make_synthetic_sequence("left30", frame_times_s=[0.5])
    gray = cv2.cvtColor(seq.frames[0].rgb, cv2.COLOR_BGR2GRAY)
    expected = {"sift": (np.float32, 128), "surf": (np.float32, 64), "orb": (np.uint8, 32),
                "fast": (np.uint8, 32), "akaze": (np.uint8, 61), "brisk": (np.uint8, 64)}
    for name, (dtype, dims) in expected.items():
        kps, desc = imumatch.extract_features(gray, name, 500)
        assert 100 < len(kps) <= 500, name
        assert desc.dtype == dtype and desc.shape == (len(kps), dims), name
        assert not desc.flags["OWNDATA"]  # a view of the C++ matrix, not a copy
    opts = imumatch.FeatureOptions()
    opts.detector = "orb"
    opts.max_keypoints = 200
    kps, _ = imumatch.extract_features(gray, options=opts)
    assert len(kps) <= 200
    # ORB split between two tasks: as many features, strongest first, mostly the same positions.
    opts.threads = 2
    split, _ = imumatch.extract_features(gray, options=opts)
    assert len(split) == len(kps)
    assert (np.diff(split[:, 4]) <= 0).all()  # response column, non-increasing
    same = {(round(x, 2), round(y, 2)) for x, y in kps[:, :2]}
    assert sum((round(x, 2), round(y, 2)) in same for x, y in split[:, :2]) >= 0.8 * len(kps)
    opts.threads = 0
    with pytest.raises(ValueError):
        opts.check()
    # Every brute-force path this CPU runs gives the same matches.
    _, d2 = imumatch.extract_features(gray, "sift", 300)
    for desc in (d1 := imumatch.extract_features(gray, "orb", 500)[1], d2):
        ref = imumatch.match_brute_force(desc, desc[::-1].copy(), kernel="scalar")
        for k in imumatch.brute_force_kernels():
            got = imumatch.match_brute_force(desc, desc[::-1].copy(), kernel=k)
            assert (got.train_idx == ref.train_idx).all() and (got.distance == ref.distance).all()
    with pytest.raises(ValueError):
        imumatch.match_brute_force(d1, d1, kernel="avx1024")
    # Own brute force and OpenCV's agree on most matches of the same descriptors.
    _, d1 = imumatch.extract_features(gray, "orb", 500)
    own = imumatch.match_brute_force(d1, d1, ratio=1.0)
    assert (own.query_idx == own.train_idx).all() and (own.distance == 0).all()


def test_segments_near_end_from_the_scene_without_depth():
    seq, motion, gray_a, gray_b = synthetic_pair()
    kps_a, desc_a = imumatch.extract_features(gray_a, "orb", 1000)
    kps_b, desc_b = imumatch.extract_features(gray_b, "orb", 1000)
    fixed = imumatch.PredictionOptions()
    fixed.scene_near.enabled = False
    adapted = imumatch.match_guided(seq.camera, motion, kps_a, desc_a, kps_b, desc_b)
    plain = imumatch.match_guided(seq.camera, motion, kps_a, desc_a, kps_b, desc_b,
                                  prediction_options=fixed)
    assert plain.segment_near_m == pytest.approx(0.1)
    # The synthetic room lies metres away: the segments start far beyond 0.1 m ...
    assert adapted.segment_near_m > 0.1
    assert adapted.stats["points_scanned"] < plain.stats["points_scanned"]
    # ... and the matches still agree with the exact poses and the rendered depth.
    fa, fb = seq.frames
    gt = imumatch.camera_motion_from_poses(fa.t_ns, fa.world_from_cam, fb.t_ns, fb.world_from_cam)
    correct = []
    for result in (adapted, plain):
        uv_a = kps_a[result.query_idx, :2]
        z = fa.depth[np.round(uv_a[:, 1]).astype(int), np.round(uv_a[:, 0]).astype(int)] / 5000.0
        ok = z > 0
        p_b = gt.cam_b_from_cam_a.transform(seq.camera.unproject(uv_a[ok], z[ok]))
        err = np.linalg.norm(seq.camera.project(p_b) - kps_b[result.train_idx[ok], :2], axis=1)
        correct.append(int(np.sum(err < 3.0)))
    assert correct[0] >= 0.98 * correct[1]
    assert correct[0] > 200


def test_a_fisheye_is_detected_and_matched_within_its_field_of_view():
    # TUM-VI's lens reaches 108 deg at the corners; the matcher's field ends at 80 deg. Which
    # pixels lie within it is checked against OpenCV's own fisheye model (cv2.fisheye, an
    # independent inverse of the equidistant lens).
    cam = imumatch.PinholeCamera.tum_vi_cam0()
    assert cam.wider_than_field()
    assert not imumatch.PinholeCamera.euroc_cam0().wider_than_field()
    assert imumatch.field_of_view_mask(imumatch.PinholeCamera.euroc_cam0()) is None
    mask = imumatch.field_of_view_mask(cam)
    assert mask.shape == (512, 512) and mask.dtype == np.uint8
    rng = np.random.default_rng(5)
    uv = rng.uniform(-0.5, 511.5, size=(4000, 2))
    distorted = np.hypot((uv[:, 0] - cam.cx) / cam.fx, (uv[:, 1] - cam.cy) / cam.fy)
    uv = uv[distorted < 1.5]  # below 86 deg: cv2.fisheye folds rays beyond 90 deg back
    dist = np.array(cam.distortion[:4])
    xy = cv2.fisheye.undistortPoints(uv.reshape(-1, 1, 2), cam.K, dist).reshape(-1, 2)
    theta = np.degrees(np.arctan(np.linalg.norm(xy, axis=1)))
    inside = cam.in_field(uv)
    clear = np.abs(theta - 80.0) > 0.01
    assert clear.sum() > 3000 and 100 < (~inside).sum()
    np.testing.assert_array_equal(inside[clear], theta[clear] <= 80.0)
    pixels = np.floor(uv + 0.5).astype(int)
    np.testing.assert_array_equal(mask[pixels[:, 1], pixels[:, 0]] == 255,
                                  cam.in_field(pixels.astype(np.float64)))
    # A frame rendered through the lens: detected within the field only (to the pixel the mask is
    # read at; ORB's coarser levels read it at their own pixels), the cap kept.
    seq = imumatch.make_synthetic_sequence("walk", frame_times_s=[1.0], camera=cam)
    gray = cv2.cvtColor(seq.frames[0].rgb, cv2.COLOR_BGR2GRAY)
    vs, us = np.nonzero(mask)
    edge_px = np.hypot((us - cam.cx) / cam.fx, (vs - cam.cy) / cam.fy).max() * cam.fx
    for detector in ("orb", "sift"):
        kp, desc = imumatch.extract_features(gray, detector, 500, mask=mask)
        assert len(kp) == 500 and desc.shape[0] == 500
        r_px = np.hypot((kp[:, 0] - cam.cx) / cam.fx, (kp[:, 1] - cam.cy) / cam.fy) * cam.fx
        assert r_px.max() < edge_px + 4.0
        assert cam.in_field(kp[:, :2]).mean() > 0.98
    with pytest.raises(ValueError):
        imumatch.extract_features(gray, "orb", 500, mask=mask[:100])


def test_klt_tracks_seeded_by_the_imu_land_where_the_exact_poses_put_them():
    seq, motion, gray_a, gray_b = synthetic_pair()
    fa, fb = seq.frames
    kps_a, _ = imumatch.extract_features(gray_a, "orb", 500)
    predictions = imumatch.predict_keypoints(seq.camera, motion, kps_a, depth_image=fa.depth)
    seeded = imumatch.track_klt(seq.camera, gray_a, gray_b, kps_a, predictions)
    unseeded = imumatch.track_opencv_lk(gray_a, gray_b, kps_a)
    # Independent truth: A's keypoints moved by the exact poses and the rendered depth.
    gt = imumatch.camera_motion_from_poses(fa.t_ns, fa.world_from_cam, fb.t_ns, fb.world_from_cam)
    uv_a = kps_a[:, :2]
    z = fa.depth[np.round(uv_a[:, 1]).astype(int), np.round(uv_a[:, 0]).astype(int)] / 5000.0
    truth = np.full((len(kps_a), 2), np.nan)
    ok = z > 0
    truth[ok] = seq.camera.project(gt.cam_b_from_cam_a.transform(
        seq.camera.unproject(uv_a[ok], z[ok])))
    for tracks in (seeded, unseeded):
        t = tracks["tracked"] & ok
        assert t.sum() == np.count_nonzero(~np.isnan(tracks["uv_b"][:, 0]) & ok)
        err = np.linalg.norm(tracks["uv_b"][t] - truth[t], axis=1)
        assert np.mean(err < 1.0) > 0.95, np.percentile(err, [50, 90, 99])
        assert tracks["stats"]["tracked"] == int(tracks["tracked"].sum())
        assert len(tracks["outcomes"]) == len(kps_a)
        assert tracks["outcomes"].count("tracked") == tracks["stats"]["tracked"]
    assert seeded["tracked"].sum() > 300
    # The seeds are the predictions, mapped into the image: near the truth.
    t = seeded["tracked"] & ok
    assert np.median(np.linalg.norm(seeded["seed_uv_b"][t] - truth[t], axis=1)) < 2.0
    assert np.isnan(unseeded["seed_uv_b"]).all()


def test_klt_refuses_mismatched_inputs():
    seq, motion, gray_a, gray_b = synthetic_pair()
    kps_a, _ = imumatch.extract_features(gray_a, "orb", 200)
    predictions = imumatch.predict_keypoints(seq.camera, motion, kps_a)
    with pytest.raises(ValueError, match="predictions for"):
        imumatch.track_klt(seq.camera, gray_a, gray_b, kps_a[:10], predictions)
    with pytest.raises(ValueError, match="one size"):
        imumatch.track_opencv_lk(gray_a, gray_b[:100], kps_a)
    with pytest.raises(ValueError, match="uint8 gray"):
        imumatch.track_klt(seq.camera, gray_a.astype(np.float32), gray_b, kps_a, predictions)
    options = imumatch.KltOptions()
    options.half_size = 0
    with pytest.raises(ValueError):
        imumatch.track_klt(seq.camera, gray_a, gray_b, kps_a, predictions, options)

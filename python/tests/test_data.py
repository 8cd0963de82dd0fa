"""Datasets and the evaluation through the bindings: the real EuRoC MH_05 excerpt, the TUM pair
(equal to the `imumatch eval` command's summary) and an in-memory synthetic sequence."""

import csv
import os
import subprocess
import tempfile

import cv2
import numpy as np
import pytest

import imumatch
from conftest import data_dir


def test_euroc_flight_loads_with_its_depth_frames():
    ds = imumatch.load_dataset(os.path.join(data_dir(), "euroc_mh05_flight"))
    assert ds.kind == "euroc" and len(ds) == 200
    assert sum(1 for f in ds.frames if f.depth_path) == 36
    assert ds.camera.width == 752 and ds.camera.distortion[0] == pytest.approx(-0.2834, abs=1e-3)
    assert not ds.imu_simulated and len(ds.imu) > 1000
    assert ds.frames[0].world_from_cam is not None
    image, depth = ds.read_frame(0)
    assert image.shape == (480, 752) and image.dtype == np.uint8
    assert depth.shape == (480, 752) and depth.dtype == np.uint16
    assert ds.read_frame(100)[1] is None  # no depth image for this frame
    # The IMU's timestamps are int64 nanoseconds as in data.csv (EuRoC's carry 256 ns steps:
    # 1403638518097829376, ...102829568), sorted, at 200 Hz.
    t = ds.imu.t_ns
    assert t.dtype == np.int64 and t[0] == 1403638518097829376 and t[1] == 1403638518102829568
    assert (np.diff(t) > 0).all() and abs(np.median(np.diff(t)) - 5_000_000) < 300
    # The log starts on the ground: the still start gives a bias near the evaluation's.
    init = imumatch.initialize_from_still(ds.imu, ds.imu.begin_ns, ds.imu.begin_ns + 1_000_000_000,
                                          ds.imu_params)
    assert np.allclose(init.bias.gyro, [-1.88e-3, 2.01e-2, 7.80e-2], atol=2e-3)


def test_evaluate_equals_the_eval_command_on_the_tum_pair():
    pair = os.path.join(data_dir(), "tum_fr1_xyz_pair")
    rows = imumatch.evaluate(pair, detectors=["orb", "sift"], methods=["bf", "guided"])
    assert [(r["detector"], r["method"]) for r in rows] == [
        ("sift", "bf"), ("sift", "guided"), ("orb", "bf"), ("orb", "guided")]
    cli = os.path.join(os.path.dirname(os.environ["IMUMATCH_PYTHON_REFERENCE"]), "..", "apps",
                       "imumatch")
    with tempfile.TemporaryDirectory() as out:
        subprocess.run([cli, "eval", pair, "--detectors", "orb,sift", "--methods", "bf,guided",
                        "--e2e-frames", "0", "--images", "0", "--out", out],
                       check=True, capture_output=True, timeout=240)
        with open(os.path.join(out, "summary.csv")) as f:
            cli_rows = list(csv.DictReader(f))
    assert len(cli_rows) == len(rows)
    for r, c in zip(rows, cli_rows):
        assert c["detector"] == r["detector"]
        assert float(c["matches"]) == pytest.approx(r["matches"])
        assert float(c["correct"]) == pytest.approx(r["correct"])
        assert float(c["precision"]) == pytest.approx(r["precision"], abs=1e-6)
    guided = {r["detector"]: r for r in rows if r["method"] == "guided"}
    assert guided["orb"]["window_recall"] > 0.98


def test_evaluate_a_synthetic_sequence_in_memory():
    seq = imumatch.make_synthetic_sequence("front1m", frame_times_s=[1.0, 1.033, 1.066])
    out = imumatch.evaluate(seq, detectors=["orb"], methods=["bf", "guided"], details=True)
    assert out["pairs"] == 2 and out["threshold_px"] == 1.5 and not out["skipped"]
    bf, guided = out["rows"]
    assert guided["method"] == "guided" and guided["pairs"] == 2
    assert guided["precision"] > 0.95 and guided["correct"] >= bf["correct"]
    assert "front1m" in imumatch.motion_names()
    # One match per query and method: kept + gained is guided's correct count and the brute-force
    # correct matches checked are brute force's, over both pairs.
    (fate,) = out["bf_correct_fate"]
    assert fate["method"] == "guided" and fate["detector"] == "orb"
    assert fate["checked"] == round(bf["correct"] * bf["pairs"])
    assert fate["kept"] + fate["gained"] == round(guided["correct"] * guided["pairs"])
    assert fate["kept"] + fate["matched_wrong"] <= fate["checked"]


def test_tum_trajectory_reader(tmp_path):
    p = tmp_path / "traj.txt"
    p.write_text("# t tx ty tz qx qy qz qw\n1.5 1 2 3 0 0 0 1\n2.0 0 0 0 0 0 0.70710678 0.70710678\n")
    poses = imumatch.read_tum_trajectory(str(p))
    assert [t for t, _ in poses] == [1_500_000_000, 2_000_000_000]
    assert np.allclose(poses[0][1].translation, [1, 2, 3])
    assert imumatch.rotation_distance_deg(poses[1][1], poses[0][1]) == pytest.approx(90.0)


def test_the_second_pass_finds_more_on_the_seed_pair():
    # The paper's seed pair (turn left 30 deg over 2 s): the IMU's 2 s prediction is good to tens
    # of pixels, the motion fitted to the first pass's matches to a fraction of one. Judged by the
    # exact synthetic ground truth, as the C++ test EvaluationTest.TheSecondPass... does.
    seq = imumatch.make_synthetic_sequence("left30", frame_times_s=[0.5, 2.5])
    rows = {}
    for second_pass in (False, True):
        out = imumatch.evaluate(seq, detectors=["orb"], methods=["bf", "guided"],
                                second_pass=second_pass)
        rows[second_pass] = {r["method"]: r for r in out}
    one, two = rows[False]["guided"], rows[True]["guided"]
    assert rows[False]["bf"]["correct"] == rows[True]["bf"]["correct"]
    assert two["correct"] > 1.03 * one["correct"]
    assert two["precision"] >= one["precision"]


def test_a_monocular_evaluation_predicts_without_depth_and_judges_with_it():
    # The synthetic room (exact depth and poses): every keypoint is predicted along its epipolar
    # segment, as for a camera without depth, and the depth images judge the matches exactly.
    seq = imumatch.make_synthetic_sequence("front1m", frame_times_s=[1.0, 1.033, 1.066])
    rows = {}
    for monocular in (False, True):
        out = imumatch.evaluate(seq, detectors=["orb"], methods=["bf", "guided"],
                                monocular=monocular)
        rows[monocular] = {r["method"]: r for r in out}
    rgbd, mono = rows[False]["guided"], rows[True]["guided"]
    assert rows[False]["bf"]["correct"] == rows[True]["bf"]["correct"]
    assert mono["correct"] != rgbd["correct"]  # it did predict otherwise
    assert mono["window_recall"] >= 0.99
    assert mono["correct"] >= rows[True]["bf"]["correct"]
    assert mono["precision"] >= rows[True]["bf"]["precision"]


def test_a_synthetic_sequence_through_a_lens_agrees_with_opencv_undistortion():
    # EuRoC's lens at half size. A pixel of the image rendered through the lens shows what the
    # lens-free camera with the same K shows at the pixel OpenCV's undistortPoints (an independent
    # inverse of the radial-tangential model) gives it: the same depth, bilinearly interpolated.
    k = [229.327, 228.648, 183.3575, 124.1875]
    dist = [-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05, 0.0]
    lens = imumatch.PinholeCamera(376, 240, *k, distortion=dist)
    plain = imumatch.PinholeCamera(376, 240, *k)
    seq = imumatch.make_synthetic_sequence("walk", frame_times_s=[1.0], camera=lens)
    assert seq.camera.has_distortion()
    through_lens = seq.frames[0].depth.astype(np.float64)
    without = imumatch.make_synthetic_sequence("walk", frame_times_s=[1.0], camera=plain)
    without = without.frames[0].depth.astype(np.float64)
    rng = np.random.default_rng(3)
    uv = np.column_stack([rng.integers(0, 376, 600), rng.integers(0, 240, 600)]).astype(np.float64)
    ideal = cv2.undistortPoints(uv.reshape(-1, 1, 2), lens.K, np.array(dist), P=lens.K)
    ideal = ideal.reshape(-1, 2)

    def bilinear(img, x, y):
        x0, y0 = int(np.floor(x)), int(np.floor(y))
        if x0 < 0 or y0 < 0 or x0 + 1 >= img.shape[1] or y0 + 1 >= img.shape[0]:
            return np.nan
        patch = img[y0:y0 + 2, x0:x0 + 2]
        if (patch == 0).any():
            return np.nan
        fx, fy = x - x0, y - y0
        return ((1 - fx) * (1 - fy) * patch[0, 0] + fx * (1 - fy) * patch[0, 1] +
                (1 - fx) * fy * patch[1, 0] + fx * fy * patch[1, 1])

    rel, rel_naive = [], []
    for (u, v), (x, y) in zip(uv, ideal):
        d = through_lens[int(v), int(u)]
        expected = bilinear(without, x, y)
        if d > 0 and np.isfinite(expected):
            rel.append(abs(d - expected) / expected)
            rel_naive.append(abs(d - without[int(v), int(u)]) / d)
    rel, rel_naive = np.array(rel), np.array(rel_naive)
    assert len(rel) > 300
    # Smooth surfaces agree to the interpolation's error; a few samples straddle an edge.
    assert np.median(rel) < 0.002
    assert np.mean(rel < 0.01) > 0.95
    # Reading the same pixel of the lens-free image instead is far off: the lens matters here.
    assert np.median(rel_naive) > 5 * np.median(rel)


def test_a_synthetic_sequence_written_in_both_layouts_loads_back(tmp_path):
    seq = imumatch.make_synthetic_sequence("left30", frame_times_s=[1.0, 1.05, 1.1])
    imumatch.write_synthetic_sequence(seq, str(tmp_path / "tum"))
    imumatch.write_synthetic_sequence(seq, str(tmp_path / "euroc"), format="euroc")
    for folder in ("tum", "euroc"):
        d = imumatch.load_dataset(str(tmp_path / folder))
        assert len(d) == 3
        assert d.camera.fx == seq.camera.fx
        gray, depth = d.read_frame(1)
        assert gray.shape == (480, 640) and depth.dtype == np.uint16
        assert np.array_equal(depth, seq.frames[1].depth)
    with pytest.raises(ValueError):
        imumatch.write_synthetic_sequence(seq, str(tmp_path / "x"), format="kitti")
    assert imumatch.read_camera(os.path.join(data_dir(), "euroc_mh05_flight", "mav0", "cam0",
                                             "sensor.yaml")).width == 752


def test_evaluate_reports_the_cameras_clock_offset_on_the_real_flight():
    out = imumatch.evaluate(os.path.join(data_dir(), "euroc_mh05_flight"), detectors=["orb"],
                            methods=["guided"], max_pairs=40, details=True)
    (t,) = out["time_offsets"]
    assert t["case"] == "euroc_mh05_flight" and t["detector"] == "orb"
    assert t["measured"], t["reason"]
    assert abs(t["offset_s"]) < max(3 * t["sigma_s"], 0.0015)
    assert not any("clocks look" in w for w in out["warnings"])


def test_track_measures_the_cameras_clock_offset_on_the_real_flight():
    # MH_05's camera is triggered by the IMU's clock: the fitted rotations of 60 frames find no
    # offset worth setting, and say how well they know it.
    out = imumatch.track(os.path.join(data_dir(), "euroc_mh05_flight"), max_frames=60)
    t = out["time_offset"]
    assert t["measured"], t["reason"]
    assert t["observations"] >= 30 and 0 < t["sigma_s"] < 0.001
    # The sigma is the larger of the parabola's and the block jackknife's (10 runs of the fits).
    assert 0 < t["jackknife_sigma_s"] <= t["sigma_s"]
    assert abs(t["offset_s"]) < max(3 * t["sigma_s"], 0.0015)
    assert not any("clocks look" in w for w in out["warnings"])
    assert out["imu_time_offset_s"] == 0.0  # no online estimate asked for: read at the stamps


def test_an_offset_not_measured_has_no_number():
    # 8 frames give fewer fitted rotations than the estimate needs: not measured, and no
    # offset or sigma that could be read as exact.
    out = imumatch.track(os.path.join(data_dir(), "euroc_mh05_flight"), max_frames=8)
    t = out["time_offset"]
    assert t is not None and not t["measured"]
    assert t["offset_s"] is None and t["sigma_s"] is None and t["jackknife_sigma_s"] is None
    assert "needed" in t["reason"], t["reason"]


def test_the_front_end_tracks_a_synthetic_walk_without_ground_truth():
    # Frames after the walk's 0.5 s still start; the IMU log starts at t = 0, so the front end
    # takes gravity and bias from the still part. The ground truth only judges afterwards.
    times = [0.6 + k / 30.0 for k in range(12)]
    seq = imumatch.make_synthetic_sequence("walk", frame_times_s=times)
    out = imumatch.track(seq, detector="orb")
    frames = out["frames"]
    assert len(frames) == 12 and out["fallbacks"] == 0
    assert frames[0]["status"] == "first"
    assert all(f["status"] == "guided" for f in frames[1:])
    assert all(isinstance(f["world_from_cam"], imumatch.Rigid3d) for f in frames)
    # Against the exact poses: millimetres and hundredths of a degree per frame.
    assert out["rpe"]["pairs"] == 11
    assert out["rpe"]["rmse_translation_m"] < 0.003
    assert out["rpe"]["rmse_rotation_deg"] < 0.05
    judged = [f for f in frames[1:] if f["judged"]]
    assert len(judged) == 11
    assert min(f["precision"][1.0] for f in judged) > 0.97
    assert min(f["matches"] for f in judged) > 500
    # A dataset without an IMU cannot be tracked: the error says so.
    with pytest.raises(imumatch.InputError):
        imumatch.track(os.path.join(data_dir(), "tum_fr1_xyz_pair"))


def test_a_tum_vi_like_folder_loads_with_kalibr_files_mocap_poses_and_16_bit_frames(tmp_path):
    # TUM-VI's exports: the EuRoC layout without sensor.yaml files (Kalibr's camchain.yaml and
    # imu_config.yaml in dso/), ground truth as mocap0 poses, 16-bit frames.
    cam = imumatch.PinholeCamera.tum_vi_cam0()
    seq = imumatch.make_synthetic_sequence("walk", frame_times_s=[1.0, 1.05], camera=cam)
    imumatch.write_synthetic_sequence(seq, str(tmp_path), format="euroc")
    mav0 = tmp_path / "mav0"
    euroc = imumatch.load_dataset(str(tmp_path))
    (mav0 / "cam0" / "sensor.yaml").unlink()
    (mav0 / "imu0" / "sensor.yaml").unlink()
    (tmp_path / "dso").mkdir()
    m = euroc.cam_from_imu.matrix()
    rows = "".join("  - [%s]\n" % ", ".join(repr(float(v)) for v in m[r]) for r in range(4))
    d = ", ".join(repr(float(v)) for v in cam.distortion[:4])
    (tmp_path / "dso" / "camchain.yaml").write_text(
        "cam0:\n  T_cam_imu:\n" + rows + "  camera_model: pinhole\n"
        "  distortion_model: equidistant\n  distortion_coeffs: [%s]\n"
        "  intrinsics: [%r, %r, %r, %r]\n  resolution: [512, 512]\n"
        % (d, cam.fx, cam.fy, cam.cx, cam.cy))
    p = euroc.imu_params
    (tmp_path / "dso" / "imu_config.yaml").write_text(
        "accelerometer_noise_density: %r\naccelerometer_random_walk: %r\n"
        "gyroscope_noise_density: %r\ngyroscope_random_walk: %r\nupdate_rate: %r\n"
        % (p.accel_noise_density, p.accel_random_walk, p.gyro_noise_density,
           p.gyro_random_walk, p.rate_hz))
    states = (mav0 / "state_groundtruth_estimate0" / "data.csv").read_text().splitlines()
    (mav0 / "mocap0").mkdir()
    (mav0 / "mocap0" / "data.csv").write_text(
        "".join(",".join(line.split(",")[:8]) + "\n" for line in states if line[0] != "#"))
    for f in (mav0 / "state_groundtruth_estimate0").iterdir():
        f.unlink()
    (mav0 / "state_groundtruth_estimate0").rmdir()
    first = sorted((mav0 / "cam0" / "data").iterdir())[0]
    gray8 = cv2.imread(str(first), cv2.IMREAD_GRAYSCALE)
    cv2.imwrite(str(first), gray8.astype(np.uint16) * 257)
    ds = imumatch.load_dataset(str(tmp_path))
    assert any("camchain.yaml" in w for w in ds.warnings)
    assert any("mocap0" in w for w in ds.warnings)
    np.testing.assert_allclose(ds.cam_from_imu.matrix(), m, atol=1e-12)
    assert ds.camera.wider_than_field()
    image, _ = ds.read_frame(0)
    assert image.dtype == np.uint8
    np.testing.assert_array_equal(image, gray8)
    # Poses equal, velocities from the poses' slope.
    for a, b in zip(ds.frames, euroc.frames):
        np.testing.assert_allclose(a.world_from_cam.matrix(), b.world_from_cam.matrix(), atol=1e-9)


def test_the_per_frame_front_end_equals_track_over_the_same_walk():
    # Fed as `track` feeds it (the IMU up to one sample past each frame, then the frame), the
    # per-frame FrontEnd gives the same statuses, match counts and poses as imumatch.track.
    times = [0.6 + k / 30.0 for k in range(8)]
    seq = imumatch.make_synthetic_sequence("walk", frame_times_s=times)
    ref = imumatch.track(seq, detector="orb", still_s=0.5)["frames"]
    fe = imumatch.FrontEnd(seq.camera, seq.imu_params, seq.cam_from_imu, detector="orb",
                           still_s=0.5)
    imu = seq.imu
    t, gyro, accel = imu.t_ns, imu.gyro, imu.accel
    next_imu = 0
    for k, frame in enumerate(seq.frames):
        while next_imu < len(t):
            fe.add_imu(int(t[next_imu]), gyro[next_imu], accel[next_imu])
            next_imu += 1
            if t[next_imu - 1] >= frame.t_ns:
                break
        r = fe.process(frame.t_ns, cv2.cvtColor(frame.rgb, cv2.COLOR_BGR2GRAY), frame.depth)
        assert r["status"] == ref[k]["status"]
        assert len(r["matches"]) == ref[k]["matches"]
        assert r["matches"].dtype == np.int32 and r["matches"].shape[1] == 2
        if k > 0:
            # Indices into the previous frame's and this frame's keypoints.
            assert r["matches"][:, 1].max() < len(r["keypoints"])
            np.testing.assert_allclose(r["world_from_cam"].matrix(),
                                       ref[k]["world_from_cam"].matrix(), atol=1e-9)
            # And the estimated motion is the exact one to millimetres.
            truth = frame.world_from_cam.inverse() * seq.frames[k - 1].world_from_cam
            err = r["cam_from_prev"].inverse() * truth
            assert np.linalg.norm(err.matrix()[:3, 3]) < 0.003
    assert any("gravity" in n for n in fe.notes)
    # The gyro bias in use: the still start's (the simulated IMU's is zero, within its noise),
    # kept after a still start (learnt only without one).
    assert fe.gyro_bias.shape == (3,) and np.abs(fe.gyro_bias).max() < 2e-3
    assert not any("gyro bias learnt" in n for n in imumatch.track(seq, still_s=0.5)["notes"])
    assert imumatch.track(seq, still_s=0.5, learn_gyro_bias=False)["frames"]
    # Bad input: a frame not after the previous one, an image of another size.
    with pytest.raises(ValueError):
        fe.process(seq.frames[-1].t_ns, cv2.cvtColor(seq.frames[-1].rgb, cv2.COLOR_BGR2GRAY))
    with pytest.raises(ValueError):
        fe.process(seq.frames[-1].t_ns + 10**8, np.zeros((10, 10), np.uint8))

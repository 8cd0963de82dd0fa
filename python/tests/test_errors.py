"""Bad input raises the library's errors as Python exceptions with the same messages, and
repeated calls leak neither references nor memory."""

import gc
import sys

import numpy as np
import pytest

import imumatch


def test_exception_types():
    assert issubclass(imumatch.InputError, ValueError)
    assert issubclass(imumatch.InvalidArgument, ValueError)
    assert issubclass(imumatch.OutOfRange, IndexError)


def test_missing_dataset_names_the_path():
    with pytest.raises(imumatch.InputError) as e:
        imumatch.load_dataset("/nonexistent/folder")
    assert "/nonexistent/folder" in str(e.value) and e.value.file == "/nonexistent/folder"


def test_malformed_line_names_file_and_line(tmp_path):
    p = tmp_path / "traj.txt"
    p.write_text("1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 0 1\n3.0 0 0 zero 0 0 0 1\n")
    with pytest.raises(imumatch.InputError) as e:
        imumatch.read_tum_trajectory(str(p))
    assert e.value.line == 3 and e.value.file == str(p)
    assert str(e.value).startswith(str(p) + ":3:")


def test_unsorted_and_nan_imu_rows():
    t = np.array([0, 5_000_000, 4_000_000], dtype=np.int64)
    with pytest.raises(imumatch.InputError) as e:
        imumatch.ImuBuffer.from_arrays(t, np.zeros((3, 3)), np.zeros((3, 3)))
    assert e.value.line == 3
    gyro = np.zeros((3, 3))
    gyro[1, 2] = np.nan
    with pytest.raises(imumatch.InputError) as e:
        imumatch.ImuBuffer.from_arrays(np.array([0, 5, 10], dtype=np.int64) * 1_000_000, gyro,
                                       np.zeros((3, 3)))
    assert e.value.line == 2
    with pytest.raises(imumatch.InvalidArgument):
        imumatch.ImuBuffer.from_arrays(t, np.zeros((2, 3)), np.zeros((3, 3)))


def test_out_of_range_and_invalid_arguments():
    buf = imumatch.ImuBuffer.from_arrays(np.array([0, 5_000_000], dtype=np.int64), np.zeros((2, 3)),
                                         np.zeros((2, 3)))
    with pytest.raises(imumatch.OutOfRange):
        buf.interpolate(10_000_000)
    with pytest.raises(imumatch.InvalidArgument):
        imumatch.PinholeCamera(-640, 480, 525, 525, 319.5, 239.5)
    with pytest.raises(ValueError):
        imumatch.extract_features(np.zeros((0, 0), np.uint8), "orb")
    with pytest.raises(ValueError):
        imumatch.extract_features(np.zeros((48, 64), np.float64), "orb")
    with pytest.raises(ValueError):
        imumatch.extract_features(np.zeros((48, 64), np.uint8), "nosuchdetector")
    cam = imumatch.PinholeCamera()
    motion = imumatch.CameraMotion(imumatch.Rigid3d())
    kps = np.array([[10.0, 10.0, 7, 0, 0, 0, -1]])
    with pytest.raises(ValueError, match="one descriptor row per keypoint"):
        imumatch.match_guided(cam, motion, kps, np.zeros((2, 32), np.uint8), kps,
                              np.zeros((1, 32), np.uint8))
    with pytest.raises(ValueError, match="depth_a"):
        imumatch.match_guided(cam, motion, kps, np.zeros((1, 32), np.uint8), kps,
                              np.zeros((1, 32), np.uint8), depth_a=np.zeros((480, 640), np.float32))
    with pytest.raises(ValueError, match="differ in size"):
        imumatch.match_guided(cam, motion, kps, np.zeros((1, 32), np.uint8), kps,
                              np.zeros((1, 32), np.uint8), image_a=np.zeros((480, 640), np.uint8),
                              image_b=np.zeros((240, 320), np.uint8))
    with pytest.raises(ValueError):
        imumatch.predict_keypoints(cam, motion, np.zeros((3, 5)))
    # A depth image or frames of another size than the camera's: depths and patches would be read
    # at the wrong pixels (they were, silently).
    with pytest.raises(ValueError, match="depth_image is 10x10, the camera 640x480"):
        imumatch.predict_keypoints(cam, motion, kps[:, :2],
                                   depth_image=np.zeros((10, 10), np.uint16))
    with pytest.raises(ValueError, match="depth_a is 320x240, the camera 640x480"):
        imumatch.match_guided(cam, motion, kps, np.zeros((1, 32), np.uint8), kps,
                              np.zeros((1, 32), np.uint8), depth_a=np.zeros((240, 320), np.uint16))
    with pytest.raises(ValueError, match="image_a is 320x240, the camera 640x480"):
        imumatch.match_guided(cam, motion, kps, np.zeros((1, 32), np.uint8), kps,
                              np.zeros((1, 32), np.uint8), image_a=np.zeros((240, 320), np.uint8),
                              image_b=np.zeros((240, 320), np.uint8))


def rss_kib():
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    return 0


def test_no_leaks_over_1000_calls():
    rng = np.random.default_rng(5)
    cam = imumatch.PinholeCamera.tum_freiburg1()
    motion = imumatch.CameraMotion(imumatch.Rigid3d(np.eye(3), [0.01, 0.0, 0.0]))
    kps = np.column_stack([rng.uniform(20, 620, 300), rng.uniform(20, 460, 300),
                           np.full(300, 31.0), rng.uniform(0, 360, 300), np.zeros(300),
                           np.zeros(300), np.full(300, -1.0)])
    desc = rng.integers(0, 256, (300, 32), dtype=np.uint8)
    depth = np.full((480, 640), 10000, np.uint16)
    image = rng.integers(0, 256, (120, 160), dtype=np.uint8)

    def calls():
        r = imumatch.match_guided(cam, motion, kps, desc, kps, desc, depth_a=depth)
        _ = (r.query_idx, r.train_idx, r.distance, r.outcomes, r.stats, r.predictions.uv)
        _ = imumatch.match_brute_force(desc, desc)
        _ = imumatch.extract_features(image, "orb", 100)
        _ = cam.undistort(kps[:, :2])
        try:
            imumatch.load_dataset("/nonexistent")
        except imumatch.InputError:
            pass

    for _ in range(50):  # warm-up: caches, allocator pools
        calls()
    gc.collect()
    refs = [sys.getrefcount(x) for x in (kps, desc, depth, image, cam, motion)]
    objects = len(gc.get_objects())
    rss = rss_kib()
    for _ in range(1000):
        calls()
    gc.collect()
    assert [sys.getrefcount(x) for x in (kps, desc, depth, image, cam, motion)] == refs
    assert len(gc.get_objects()) - objects < 50
    assert rss_kib() - rss < 20 * 1024  # KiB: a leak of one 300 x 32 array per call is 9 MB


def test_every_public_name_has_a_docstring():
    import inspect

    def described(doc, name):
        # pybind11 puts the signature first; a docstring needs more than that.
        lines = [ln.strip() for ln in (doc or "").splitlines() if ln.strip()]
        return any(not (ln.startswith(name + "(") or ln.startswith("(self") or
                        ln.startswith("Overloaded") or ln[:2].rstrip(".").isdigit())
                   for ln in lines)

    missing = []
    for name in dir(imumatch):
        if name.startswith("_"):
            continue
        obj = getattr(imumatch, name)
        if inspect.isclass(obj):
            if not (obj.__doc__ or "").strip():
                missing.append(name)
            if issubclass(obj, BaseException) or hasattr(obj, "__members__"):
                continue  # exceptions and enums: the class docstring is enough
            for attr, value in vars(obj).items():
                if attr.startswith("__") and attr not in ("__init__", "__len__"):
                    continue
                if not described(getattr(value, "__doc__", ""), attr):
                    missing.append(name + "." + attr)
        elif callable(obj) and not described(obj.__doc__, name):
            missing.append(name)
    assert missing == []

"""Camera, rigid transforms and IMU through the bindings, against hand-computed values and
OpenCV's own projection (an independent implementation of the same lens model)."""

import math

import cv2
import numpy as np
import pytest

import imumatch


def test_version():
    assert imumatch.__version__.count(".") == 2


def test_pinhole_unproject_matches_the_formula():
    cam = imumatch.PinholeCamera(640, 480, 525.0, 520.0, 319.5, 239.5)
    p = cam.unproject(np.array([400.0, 100.0]), 2.0)
    assert p == pytest.approx([(400.0 - 319.5) * 2.0 / 525.0, (100.0 - 239.5) * 2.0 / 520.0, 2.0])
    assert cam.project(p) == pytest.approx([400.0, 100.0])
    # Behind the camera: NaN.
    assert np.isnan(cam.project(np.array([0.0, 0.0, -1.0]))).all()


def test_distortion_agrees_with_opencv_projectpoints():
    cam = imumatch.PinholeCamera.euroc_cam0()
    rng = np.random.default_rng(3)
    uv = np.column_stack([rng.uniform(0, cam.width - 1, 200), rng.uniform(0, cam.height - 1, 200)])
    ideal = cam.undistort(uv)
    # OpenCV's forward model on the bearings K^-1 [ideal, 1] gives back the image pixels.
    bearings = np.column_stack([(ideal[:, 0] - cam.cx) / cam.fx, (ideal[:, 1] - cam.cy) / cam.fy,
                                np.ones(len(ideal))])
    projected, _ = cv2.projectPoints(bearings, np.zeros(3), np.zeros(3), cam.K,
                                     np.array(cam.distortion))
    assert np.abs(projected.reshape(-1, 2) - uv).max() < 1e-4
    assert np.abs(cam.distort(ideal) - uv).max() < 1e-6


def test_equidistant_agrees_with_opencv_fisheye():
    cam = imumatch.PinholeCamera(752, 480, 380.0, 379.0, 370.0, 245.0,
                                 distortion=[-0.02, 0.01, -0.004, 0.0005, 0.0])
    assert cam.model == "radial-tangential"
    cam.model = "equidistant"
    cam.check()
    assert cam.has_distortion()
    rng = np.random.default_rng(5)
    uv = np.column_stack([rng.uniform(0, cam.width - 1, 200), rng.uniform(0, cam.height - 1, 200)])
    ideal = cam.undistort(uv)
    # OpenCV's fisheye model (an independent implementation of Kannala-Brandt) on the bearings.
    bearings = np.column_stack([(ideal[:, 0] - cam.cx) / cam.fx, (ideal[:, 1] - cam.cy) / cam.fy])
    projected = cv2.fisheye.distortPoints(bearings.reshape(-1, 1, 2), cam.K,
                                          np.array(cam.distortion[:4]))
    assert np.abs(projected.reshape(-1, 2) - uv).max() < 1e-4
    assert np.abs(cam.distort(ideal) - uv).max() < 1e-6
    with pytest.raises(ValueError):
        cam.model = "omnidirectional"
    # The calibration tools' aliases, as the C++ readers accept them.
    cam.model = "plumb_bob"
    assert cam.model == "radial-tangential"
    cam.model = "fisheye"
    assert cam.model == "equidistant"


def test_rigid_compose_inverse_and_transform():
    a = imumatch.Rigid3d.from_quaternion(math.cos(0.3), 0.0, 0.0, math.sin(0.3), [1.0, 2.0, 3.0])
    b = imumatch.Rigid3d(cv2.Rodrigues(np.array([0.1, -0.2, 0.3]))[0], [0.5, 0.0, -1.0])
    ab = a * b
    assert np.allclose(ab.matrix(), a.matrix() @ b.matrix())
    assert np.allclose((ab * ab.inverse()).matrix(), np.eye(4), atol=1e-12)
    pts = np.array([[1.0, 0.0, 0.0], [0.0, 2.0, 1.0]])
    expected = (a.matrix() @ np.column_stack([pts, np.ones(2)]).T).T[:, :3]
    assert np.allclose(a.transform(pts), expected)
    # Yaw of 0.6 rad about z (the quaternion's half angle 0.3).
    assert imumatch.rotation_distance_deg(a, imumatch.Rigid3d()) == pytest.approx(math.degrees(0.6))


def spinning_imu(rate=0.5, seconds=1.0, hz=200, gyro_bias=(0.0, 0.0, 0.0)):
    """A still IMU yawing at `rate` rad/s about z: the accelerometer measures +g along z."""
    n = int(seconds * hz) + 1
    t_ns = (np.arange(n) * (1e9 / hz)).astype(np.int64)
    gyro = np.tile([0.0, 0.0, rate], (n, 1)) + np.array(gyro_bias)
    accel = np.tile([0.0, 0.0, 9.81], (n, 1))
    return imumatch.ImuBuffer.from_arrays(t_ns, gyro, accel)


def test_preintegration_of_a_constant_yaw_rate():
    buf = spinning_imu()
    assert len(buf) == 201 and buf.begin_ns == 0 and buf.end_ns == 1_000_000_000
    pim = imumatch.preintegrate(buf, 0, 1_000_000_000, params=imumatch.ImuParams.ideal())
    c, s = math.cos(0.5), math.sin(0.5)
    assert np.allclose(pim.delta_rotation, [[c, -s, 0], [s, c, 0], [0, 0, 1]], atol=1e-9)
    # The specific force stays along z while yawing: dv = g t, dp = g t^2 / 2.
    assert np.allclose(pim.delta_velocity, [0, 0, 9.81], atol=1e-9)
    assert np.allclose(pim.delta_position, [0, 0, 4.905], atol=1e-9)
    assert pim.dt == pytest.approx(1.0)
    state = imumatch.NavState()
    end = imumatch.propagate(state, pim, np.array([0.0, 0.0, -9.81]))
    assert np.allclose(end.velocity_in_world, 0.0, atol=1e-9)
    assert np.allclose(end.world_from_imu.translation, 0.0, atol=1e-9)


def test_still_start_gives_the_gyro_bias():
    bias = (0.01, -0.02, 0.03)
    buf = spinning_imu(rate=0.0, gyro_bias=bias)
    init = imumatch.initialize_from_still(buf, 0, 1_000_000_000)
    assert np.allclose(init.bias.gyro, bias, atol=1e-12)
    assert np.allclose(init.gravity_in_imu, [0, 0, -9.81], atol=1e-9)
    assert init.num_samples == 201
    assert init.end_ns == 1_000_000_000


def test_a_gap_in_the_still_start_ends_it_there():
    bias = (0.01, -0.02, 0.03)
    n = 201
    t_ns = (np.arange(n) * 5_000_000).astype(np.int64)
    keep = (t_ns <= 400_000_000) | (t_ns >= 500_000_000)  # 100 ms without samples after 0.4 s
    gyro = np.tile(bias, (n, 1))
    accel = np.tile([0.0, 0.0, 9.81], (n, 1))
    buf = imumatch.ImuBuffer.from_arrays(t_ns[keep], gyro[keep], accel[keep])
    assert buf.gaps() == [(400_000_000, 500_000_000)]
    with pytest.raises(imumatch.OutOfRange):
        imumatch.preintegrate(buf, 0, 1_000_000_000)
    init = imumatch.initialize_from_still(buf, 0, 1_000_000_000)
    assert init.end_ns == 400_000_000 and init.num_samples == 81
    assert np.allclose(init.bias.gyro, bias, atol=1e-12)


def test_camera_motion_from_poses_is_the_relative_pose():
    a = imumatch.Rigid3d(np.eye(3), [0.0, 0.0, 0.0])
    b = imumatch.Rigid3d(np.eye(3), [0.1, 0.0, 0.0])  # camera B 10 cm to the right of A
    m = imumatch.camera_motion_from_poses(0, a, 33_000_000, b)
    assert m.t_b_ns == 33_000_000
    # A point 2 m ahead of A appears 10 cm to the left in B.
    assert np.allclose(m.cam_b_from_cam_a.transform(np.array([0.0, 0.0, 2.0])), [-0.1, 0.0, 2.0])

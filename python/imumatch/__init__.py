"""imumatch: IMU-guided feature matching between consecutive camera frames.

The C++ library through pybind11, with NumPy arrays in and out. Keypoints are N x 7 float64
arrays (x, y, size, angle, response, octave, class_id) or lists of ``cv2.KeyPoint``; descriptors
are N x D arrays (uint8 binary, float32 for SIFT/SURF), as OpenCV's cv2 gives them. Timestamps
are int64 nanoseconds. Errors raise ``InputError`` (bad data: a ValueError naming file and line,
with ``.file`` and ``.line``), ``InvalidArgument`` (a ValueError), ``OutOfRange`` (an IndexError)
or ``Error``.

Typical use::

    import imumatch, cv2
    kps_a, desc_a = imumatch.extract_features(gray_a, "orb")
    kps_b, desc_b = imumatch.extract_features(gray_b, "orb")
    motion = imumatch.camera_motion_from_poses(0, world_from_cam_a, 1, world_from_cam_b)
    result = imumatch.match_guided(camera, motion, kps_a, desc_a, kps_b, desc_b, depth_a=depth)
    cv2_matches = imumatch.to_cv2_matches(result)
"""

from ._imumatch import *  # noqa: F401,F403  (the extension's functions and classes)
from ._imumatch import __version__  # noqa: F401

__all__ = [name for name in dir() if not name.startswith("_")]


def to_cv2_keypoints(keypoints):
    """N x 7 keypoint array -> list of cv2.KeyPoint (needs python3-opencv)."""
    import cv2

    return [
        cv2.KeyPoint(float(k[0]), float(k[1]), float(k[2]), float(k[3]), float(k[4]),
                     int(k[5]), int(k[6]))
        for k in keypoints
    ]


def from_cv2_keypoints(keypoints):
    """List of cv2.KeyPoint -> N x 7 float64 array (x, y, size, angle, response, octave, class_id)."""
    import numpy as np

    return np.array(
        [(k.pt[0], k.pt[1], k.size, k.angle, k.response, k.octave, k.class_id) for k in keypoints],
        dtype=np.float64,
    ).reshape(-1, 7)


def to_cv2_matches(result):
    """A MatchResult -> list of cv2.DMatch (queryIdx, trainIdx, distance)."""
    import cv2

    return [
        cv2.DMatch(int(q), int(t), float(d))
        for q, t, d in zip(result.query_idx, result.train_idx, result.distance)
    ]


__all__ += ["to_cv2_keypoints", "from_cv2_keypoints", "to_cv2_matches"]

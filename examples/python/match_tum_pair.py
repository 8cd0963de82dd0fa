#!/usr/bin/env python3
"""Guided ORB matching on the TUM fr1_xyz pair, from Python.

Loads the pair (two images, the depth of the first, the two ground-truth poses), predicts with the
ground-truth motion, matches ORB keypoints inside the predicted windows and writes an image: both
frames side by side, matches green when the ground truth (depth + poses) puts them within 3 px of
their partner and red otherwise, predicted search windows in yellow.

    PYTHONPATH=build/dev/python /usr/bin/python3 examples/python/match_tum_pair.py \
        --data ../shared/data/tum_fr1_xyz_pair --out matches.png
"""

import argparse
import os

import cv2
import numpy as np

import imumatch


def window_outline(camera, bbox, steps=6):
    """The ideal-pixel window (min_x, min_y, max_x, max_y) as a polygon in the distorted image."""
    x0, y0, x1, y1 = bbox
    xs, ys = np.linspace(x0, x1, steps), np.linspace(y0, y1, steps)
    ideal = np.concatenate([np.column_stack([xs, np.full(steps, y0)]),
                            np.column_stack([np.full(steps, x1), ys]),
                            np.column_stack([xs[::-1], np.full(steps, y1)]),
                            np.column_stack([np.full(steps, x0), ys[::-1]])])
    return camera.distort(ideal)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", default="../shared/data/tum_fr1_xyz_pair")
    parser.add_argument("--out", default="tum_pair_matches.png")
    parser.add_argument("--threshold", type=float, default=3.0, help="correct-match radius (px)")
    args = parser.parse_args()

    path = lambda name: os.path.join(args.data, name)  # noqa: E731
    gray_a = cv2.imread(path("img_prev.png"), cv2.IMREAD_GRAYSCALE)
    gray_b = cv2.imread(path("img_curr.png"), cv2.IMREAD_GRAYSCALE)
    depth_a = cv2.imread(path("dep_prev.png"), cv2.IMREAD_UNCHANGED)
    if gray_a is None or gray_b is None or depth_a is None:
        raise SystemExit("cannot read the pair in %s" % args.data)
    camera = imumatch.PinholeCamera.tum_freiburg1()
    motion = imumatch.camera_motion_from_poses(0, imumatch.read_tum_pose(path("pose_prev.txt")),
                                               1, imumatch.read_tum_pose(path("pose_curr.txt")))

    kps_a, desc_a = imumatch.extract_features(gray_a, "orb", 1000)
    kps_b, desc_b = imumatch.extract_features(gray_b, "orb", 1000)
    result = imumatch.match_guided(camera, motion, kps_a, desc_a, kps_b, desc_b, depth_a=depth_a,
                                   image_a=gray_a, image_b=gray_b)
    bf = imumatch.match_opencv_knn_ratio(desc_a, desc_b, 0.8)

    def judge(query, uv_b):
        uv_a = kps_a[query, :2]
        z = depth_a[np.round(uv_a[:, 1]).astype(int), np.round(uv_a[:, 0]).astype(int)] / 5000.0
        p_b = motion.cam_b_from_cam_a.transform(camera.unproject(uv_a, np.where(z > 0, z, 1.0)))
        err = np.linalg.norm(camera.project(p_b) - uv_b, axis=1)
        return np.where(z > 0, err <= args.threshold, np.nan)

    refined = np.where(np.isnan(result.refined_uv_b), kps_b[result.train_idx, :2],
                       result.refined_uv_b)
    ok = judge(result.query_idx, refined)
    ok_bf = judge(bf.query_idx, kps_b[bf.train_idx, :2])
    for name, r, o in (("guided", result, ok), ("brute force", bf, ok_bf)):
        judged = ~np.isnan(o)
        print("%-11s %4d matches, %4d judged by depth, precision %.3f" %
              (name, len(r), judged.sum(), np.nanmean(o)))

    canvas = cv2.cvtColor(np.hstack([gray_a, gray_b]), cv2.COLOR_GRAY2BGR)
    shift = np.array([gray_a.shape[1], 0])
    preds = result.predictions
    for k, (q, good) in enumerate(zip(result.query_idx, ok)):
        outline = window_outline(camera, preds.bbox[q]) + shift
        cv2.polylines(canvas, [np.round(outline).astype(np.int32)], True, (0, 200, 255), 1)
        colour = (160, 160, 160) if np.isnan(good) else ((0, 200, 0) if good else (0, 0, 255))
        a = tuple(int(v) for v in np.round(kps_a[q, :2]))
        b = tuple(int(v) for v in np.round(refined[k] + shift))
        cv2.line(canvas, a, b, colour, 1, cv2.LINE_AA)
    cv2.putText(canvas, "imumatch %s: guided ORB, %d matches, precision %.3f (green: within %.0f px)"
                % (imumatch.__version__, len(result), np.nanmean(ok), args.threshold),
                (10, 20), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (255, 255, 255), 1, cv2.LINE_AA)
    if not cv2.imwrite(args.out, canvas):
        raise SystemExit("cannot write %s" % args.out)
    print("wrote", args.out)


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Measures when a TUM-layout sequence's depth images were captured relative to their stamps
(the camera key depth_time_offset_s; docs/dynamics.md, "Depth in time").

For every STEP-th frame that turns fast enough for the offset to matter (at least
--min-rotation-deg over 20 ms, by the ground truth), the real depth image is moved to the pose of
its colour image, taking it as captured at its stamp plus each candidate offset: every reading is
back-projected through the camera's distortion, moved with the ground-truth poses (linear / nlerp
interpolation), re-projected with the distortion and splatted (nearest surface wins). The score
is the share of the moved image's depth-edge pixels (a jump of over 10 cm across 3x3 Sobel) that
lie on an edge of the colour image (Canny, grown by one pixel); the best offset scores highest.
"as read" scores the depth without a move.

  python3 scripts/fit-depth-time-offset.py ../shared/data/tum/rgbd_dataset_freiburg1_rpy
  python3 scripts/fit-depth-time-offset.py SEQ --camera config/cameras/tum1.yaml --step 3

Needs python3-opencv, python3-numpy and python3-yaml (apt). About 0.3 s per frame and offset.
"""
import argparse
import os
import sys

import cv2
import numpy as np
import yaml


def read_list(path):
    rows = []
    with open(path) as f:
        for line in f:
            if line.strip() and not line.startswith('#'):
                rows.append(line.split())
    return rows


def pairs_of(seq):
    """(rgb stamp, rgb file, depth stamp, depth file) per frame, as the pipeline reads them."""
    assoc = os.path.join(seq, 'associations.txt')
    if os.path.exists(assoc):
        return [(float(r[0]), r[1], float(r[2]), r[3]) for r in read_list(assoc)]
    rgb = [(float(r[0]), r[1]) for r in read_list(os.path.join(seq, 'rgb.txt'))]
    depth = [(float(r[0]), r[1]) for r in read_list(os.path.join(seq, 'depth.txt'))]
    stamps = np.array([d[0] for d in depth])
    out = []
    for t, f in rgb:  # nearest depth within 20 ms (TUM's associate.py), each used once
        i = int(np.argmin(np.abs(stamps - t)))
        if abs(stamps[i] - t) < 0.02:
            out.append((t, f, depth[i][0], depth[i][1]))
    return out


def quat_to_matrix(q):
    x, y, z, w = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


class GroundTruth:
    def __init__(self, path):
        self.rows = np.array([[float(v) for v in r[:8]] for r in read_list(path)])

    def pose(self, t):
        """T_w_c at t, or None outside the trajectory."""
        g = self.rows
        i = int(np.searchsorted(g[:, 0], t))
        if i <= 0 or i >= len(g):
            return None
        a, b = g[i - 1], g[i]
        s = (t - a[0]) / (b[0] - a[0])
        qa, qb = a[4:8], b[4:8]
        if np.dot(qa, qb) < 0:
            qb = -qb
        T = np.eye(4)
        T[:3, :3] = quat_to_matrix((1 - s) * qa + s * qb)
        T[:3, 3] = (1 - s) * a[1:4] + s * b[1:4]
        return T


def rotation_deg(T):
    return np.degrees(np.arccos(np.clip((np.trace(T[:3, :3]) - 1) / 2, -1, 1)))


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('sequence', help='TUM-layout folder with groundtruth.txt')
    ap.add_argument('--camera', default=os.path.join(here, '..', 'config', 'cameras', 'tum1.yaml'),
                    help='camera YAML (default: config/cameras/tum1.yaml)')
    ap.add_argument('--offsets-ms', default='-30,-26,-23,-20,-17,-14,-10,0',
                    help='candidate offsets in ms, comma-separated')
    ap.add_argument('--step', type=int, default=6, help='every STEP-th frame (default 6)')
    ap.add_argument('--min-rotation-deg', type=float, default=0.5,
                    help='only frames turning at least this much over 20 ms (default 0.5)')
    args = ap.parse_args()
    gt_path = os.path.join(args.sequence, 'groundtruth.txt')
    if not os.path.exists(gt_path):
        sys.exit(f'{gt_path}: not found (the fit needs the ground truth)')
    cam = yaml.safe_load(open(args.camera))['camera']
    K = np.array([[cam['fx'], 0, cam['cx']], [0, cam['fy'], cam['cy']], [0, 0, 1]])
    D = np.array(cam.get('distortion', [0, 0, 0, 0, 0]), dtype=np.float64)
    W, H, factor = cam['width'], cam['height'], cam['depth_factor']
    gt = GroundTruth(gt_path)
    offsets = [float(o) / 1000 for o in args.offsets_ms.split(',')]
    u, v = np.meshgrid(np.arange(W), np.arange(H))
    pixels = np.stack([u.ravel(), v.ravel()], 1).astype(np.float64).reshape(-1, 1, 2)
    rays = cv2.undistortPoints(pixels, K, D).reshape(-1, 2)

    def move(depth_raw, T):
        z = depth_raw.ravel().astype(np.float64) / factor
        ok = z > 0
        P = np.stack([rays[ok, 0] * z[ok], rays[ok, 1] * z[ok], z[ok]], 1) @ T[:3, :3].T + T[:3, 3]
        P = P[P[:, 2] > 0.1]
        uv, _ = cv2.projectPoints(P.reshape(-1, 1, 3), np.zeros(3), np.zeros(3), K, D)
        uv = np.rint(uv.reshape(-1, 2)).astype(np.int64)
        inside = (uv[:, 0] >= 0) & (uv[:, 1] >= 0) & (uv[:, 0] < W) & (uv[:, 1] < H)
        out = np.full(W * H, np.inf)
        np.minimum.at(out, uv[inside, 1] * W + uv[inside, 0], P[inside, 2])
        out[np.isinf(out)] = 0
        return out.reshape(H, W).astype(np.float32)

    def score(gray, depth_m):
        colour = cv2.dilate((cv2.Canny(cv2.GaussianBlur(gray, (5, 5), 0), 40, 120) > 0).astype(np.uint8),
                            np.ones((3, 3), np.uint8)) > 0
        jump = np.abs(cv2.Sobel(depth_m, cv2.CV_32F, 1, 0)) + np.abs(cv2.Sobel(depth_m, cv2.CV_32F, 0, 1))
        valid = cv2.erode((depth_m > 0).astype(np.uint8), np.ones((5, 5), np.uint8)) > 0
        edges = (jump > 0.4) & valid  # Sobel sums 4 differences: 10 cm each
        return (edges & colour).sum() / max(1, edges.sum())

    totals = np.zeros(len(offsets))
    as_read = 0.0
    frames = 0
    for k, (t_rgb, rgb_file, t_depth, depth_file) in enumerate(pairs_of(args.sequence)):
        if k % args.step:
            continue
        T_w_rgb, T_w_later = gt.pose(t_rgb), gt.pose(t_rgb + 0.02)
        if T_w_rgb is None or T_w_later is None:
            continue
        if rotation_deg(np.linalg.inv(T_w_rgb) @ T_w_later) < args.min_rotation_deg:
            continue
        poses = [gt.pose(t_depth + o) for o in offsets]
        if any(p is None for p in poses):
            continue
        gray = cv2.imread(os.path.join(args.sequence, rgb_file), cv2.IMREAD_GRAYSCALE)
        depth_raw = cv2.imread(os.path.join(args.sequence, depth_file), cv2.IMREAD_UNCHANGED)
        if gray is None or depth_raw is None:
            sys.exit(f'{args.sequence}: cannot read {rgb_file} or {depth_file}')
        as_read += score(gray, depth_raw.astype(np.float32) / factor)
        for i, T_w_depth in enumerate(poses):
            totals[i] += score(gray, move(depth_raw, np.linalg.inv(T_w_rgb) @ T_w_depth))
        frames += 1
    if frames == 0:
        sys.exit('no frame turns fast enough inside the ground truth (lower --min-rotation-deg)')
    print(f'{frames} frames; share of depth-edge pixels on a colour edge:')
    print(f'  as read: {as_read / frames:.4f}')
    for o, total in zip(offsets, totals):
        print(f'  depth captured at its stamp {o * 1000:+.0f} ms: {total / frames:.4f}')
    print(f'best offset: {offsets[int(np.argmax(totals))]:+.3f} s')


if __name__ == '__main__':
    main()

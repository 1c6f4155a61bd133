#!/usr/bin/env python3
"""A similarity that puts a COLMAP model in a local east-north-up frame when
the photos' GPS heights cannot be trusted (a consumer receiver's altitude
drifts by tens of metres over a flight, and aligning to it tilts the whole
block): the plane of the camera centres of the survey strips is made level,
the model is scaled, turned and moved onto the photos' GPS east and north,
and heights are put so that the median sparse point is at 0.

    level_to_gps.py MODEL_TXT DATABASE OUT_TRANSFORM

MODEL_TXT: a text model (colmap model_converter --output_type TXT);
DATABASE: the COLMAP database whose images hold the EXIF GPS priors
(latitude, longitude); OUT_TRANSFORM: the 3 x 4 similarity for
`colmap model_transformer --transform_path`. Prints the fit's residuals.
"""
import math
import sqlite3
import sys

import numpy as np


def quat_to_r(q):
    w, x, y, z = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def main():
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    model, database, out = sys.argv[1:]
    lines = [l for l in open(f"{model}/images.txt") if not l.startswith("#")]
    names, centres, axes = [], [], []
    for header in lines[0::2]:
        p = header.split()
        r = quat_to_r(list(map(float, p[1:5])))
        t = np.array(list(map(float, p[5:8])))
        names.append(p[9])
        centres.append(-r.T @ t)
        axes.append(r[2])
    centres, axes = np.array(centres), np.array(axes)
    points = np.array([list(map(float, l.split()[1:4]))
                       for l in open(f"{model}/points3D.txt") if not l.startswith("#")])
    gps = {n: (lat, lon) for n, lat, lon in sqlite3.connect(database).execute(
        "select name, prior_tx, prior_ty from images")}
    missing = [n for n in names if n not in gps or gps[n][0] is None]
    if missing:
        sys.exit(f"{database}: no GPS prior for {', '.join(missing[:5])}")

    # The strips' plane: fitted to the centres, then again without those far
    # off it (the climb, the landing), twice.
    keep = np.ones(len(centres), bool)
    for _ in range(3):
        c = centres[keep].mean(axis=0)
        normal = np.linalg.svd(centres[keep] - c)[2][2]
        off = np.abs((centres - c) @ normal)
        keep = off <= max(3 * np.median(off[keep]), 1e-9)
    if normal @ axes.mean(axis=0) > 0:  # up is away from where the cameras look
        normal = -normal
    # Rotation taking `normal` to +z (Rodrigues).
    v = np.cross(normal, [0, 0, 1])
    s, cth = np.linalg.norm(v), normal[2]
    vx = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    level = np.eye(3) + vx + vx @ vx * ((1 - cth) / (s * s)) if s > 1e-12 else np.eye(3)
    flat = centres @ level.T

    # East and north of each photo, metres, tangent at the model's first image.
    lat0, lon0 = gps[names[0]]
    k_e = math.radians(1) * 6378137 * math.cos(math.radians(lat0))
    k_n = math.radians(1) * 6367449
    en = np.array([[(gps[n][1] - lon0) * k_e, (gps[n][0] - lat0) * k_n] for n in names])
    # 2D similarity (Umeyama) of the levelled centres onto GPS east/north.
    a, b = flat[keep, :2], en[keep]
    ma, mb = a.mean(axis=0), b.mean(axis=0)
    u, d, vt = np.linalg.svd((b - mb).T @ (a - ma))
    rot2 = u @ np.diag([1, np.sign(np.linalg.det(u @ vt))]) @ vt
    scale = d.sum() / ((a - ma) ** 2).sum()
    rot = np.eye(3)
    rot[:2, :2] = rot2
    r_total = rot @ level
    t_xy = mb - scale * rot2 @ ma
    z0 = np.median(scale * (points @ r_total.T)[:, 2])
    t = np.array([t_xy[0], t_xy[1], -z0])
    res = np.linalg.norm(scale * (flat[:, :2] @ rot2.T) + t_xy - en, axis=1)
    m = np.hstack([scale * r_total, t[:, None]])
    with open(out, "w") as f:
        for row in m:
            f.write(" ".join(f"{v:.12g}" for v in row) + "\n")
    heights = scale * (centres @ r_total.T)[:, 2] - z0
    print(f"{out}: scale {scale:.5f}, levelled by {math.degrees(math.acos(min(1, cth))):.2f} deg; "
          f"GPS east/north residuals median {np.median(res[keep]):.2f} m, max {res[keep].max():.2f} m; "
          f"{(~keep).sum()} photos off the strips' plane "
          f"({', '.join(n for n, k in zip(names, keep) if not k)}); "
          f"strip photos {np.median(heights[keep]):.1f} m above the median sparse point")


if __name__ == "__main__":
    main()

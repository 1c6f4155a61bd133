#!/usr/bin/env python3
"""Steps between neighbouring DSM cells of a grouped run, by distance to a border.

group_borders splits the pairs of neighbouring cells of a run's dsm.tif into
"inside groups" and "across borders". This splits those inside groups further
by how far (in cells) they lie from the nearest border between two group
cores, which shows whether the pairs by a border are rougher than those deep
in a group, and repeats the split for open ground only: cells within 1 unit
of the 5th percentile height of the 31 x 31 cells around (no crowns, no
roofs), where steps are the surface's and not the scene's.

    python3 profiling/border_steps.py RUN_DIR [--borders-of GROUPED_RUN_DIR] [--cloud]

--borders-of takes the group centres (and so the borders) from another run:
given a one-group run of the same block (`--max-images` above its image count,
`--dsm-cell` the grouped run's cell), it measures the same pairs on a surface
that no border touched, which tells a step the merge made from one the scene
has where a border happens to lie (a forest edge, a wall).

--cloud measures the median heights of RUN_DIR/cloud.ply on the DSM's cell
instead of dsm.tif, on four grids offset by half a cell, and prints the
across / inside rows of all four together. The DSM's grid starts at the
cloud's corner, so a change that drops one outlying point moves every cell
and redraws the p99 across borders (about 6,000 pairs on Caliterra, its
tail some 60): two clouds 2 points apart read 0.405 and 0.44 m from
dsm.tif, 0.397 and 0.394 m this way.

Needs python3-numpy and gdal-bin (gdal_translate, gdalinfo) from Debian.
Prints count, median, p90 and p99 of |dz| per set, in CRS units.
"""
import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import warnings

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view


def read_dsm(path):
    info = subprocess.run(["gdalinfo", path], capture_output=True, text=True, check=True).stdout
    w, h = map(int, re.search(r"Size is (\d+), (\d+)", info).groups())
    ox, oy = map(float, re.search(r"Origin = \(([-\d.e]+),([-\d.e]+)\)", info).groups())
    cell = float(re.search(r"Pixel Size = \(([-\d.e]+),", info).group(1))
    with tempfile.TemporaryDirectory() as tmp:
        raw = os.path.join(tmp, "dsm.bin")
        subprocess.run(["gdal_translate", "-q", "-ot", "Float32", "-of", "ENVI", path, raw],
                       check=True)
        z = np.fromfile(raw, dtype=np.float32).reshape(h, w)
    nodata = re.search(r"NoData Value=([-\w.e+]+)", info)
    empty = ~np.isfinite(z)
    if nodata and nodata.group(1).lower() != "nan":
        empty |= z == float(nodata.group(1))
    return z, empty, ox, oy, cell


def read_cloud(path):
    """x, y, z of a binary little-endian PLY as sapmvs writes it."""
    types = {"double": "<f8", "float": "<f4", "uchar": "u1", "int": "<i4", "uint": "<u4",
             "short": "<i2", "ushort": "<u2", "char": "i1"}
    with open(path, "rb") as f:
        fields, count = [], 0
        while True:
            line = f.readline().decode("ascii", "replace").split()
            if not line:
                continue
            if line[0] == "format" and line[1] != "binary_little_endian":
                sys.exit("%s: a binary little-endian PLY expected" % path)
            if line[:2] == ["element", "vertex"]:
                count = int(line[2])
            elif line[0] == "property":
                fields.append((line[2], types[line[1]]))
            elif line[0] == "end_header":
                break
        data = np.fromfile(f, dtype=np.dtype(fields), count=count)
    return data["x"].astype(float), data["y"].astype(float), data["z"].astype(float)


def cloud_grids(run, cell, centers):
    """Neighbouring cells' |dz| and whether the two share a core, over four
    grids of median heights offset by half a cell."""
    x, y, z = read_cloud(os.path.join(run, "cloud.ply"))
    dz, same = [], []
    for ox, oy in ((0, 0), (0.5, 0), (0, 0.5), (0.5, 0.5)):
        c = np.floor(x / cell - ox).astype(np.int64)
        r = np.floor(y / cell - oy).astype(np.int64)
        c0, r0 = c.min(), r.min()
        c, r = c - c0, r - r0
        w, h = c.max() + 1, r.max() + 1
        key = r * w + c
        order = np.lexsort((z, key))
        cells, start, n = np.unique(key[order], return_index=True, return_counts=True)
        zs = z[order]
        grid = np.full(h * w, np.nan)
        grid[cells] = 0.5 * (zs[start + (n - 1) // 2] + zs[start + n // 2])
        grid = grid.reshape(h, w)
        ys, xs = np.mgrid[0:h, 0:w]
        cx = (xs + c0 + ox + 0.5) * cell
        cy = (ys + r0 + oy + 0.5) * cell
        owner = np.argmin(np.stack([(cx - a) ** 2 + (cy - b) ** 2 for a, b in centers]), axis=0)
        for dr, dc in ((0, 1), (1, 0)):
            a, b = grid[:h - dr, :w - dc], grid[dr:, dc:]
            ok = np.isfinite(a) & np.isfinite(b)
            dz.append(np.abs(a - b)[ok])
            same.append((owner[:h - dr, :w - dc] == owner[dr:, dc:])[ok])
    return np.concatenate(dz), np.concatenate(same)


def quantiles(v):
    if len(v) == 0:
        return "%9d %9s %9s %9s" % (0, "-", "-", "-")
    return "%9d %9.4f %9.4f %9.4f" % (len(v), *np.quantile(v, [0.5, 0.9, 0.99]))


def main():
    parser = argparse.ArgumentParser(description="DSM steps by distance to a group border")
    parser.add_argument("run", help="run folder with dsm.tif and report.json")
    parser.add_argument("--borders-of", metavar="RUN", help="take the group centres from this run")
    parser.add_argument("--cloud", action="store_true",
                        help="median heights of cloud.ply on four offset grids, not dsm.tif")
    args = parser.parse_args()
    z, empty, ox, oy, cell = read_dsm(os.path.join(args.run, "dsm.tif"))
    h, w = z.shape
    grouped = args.borders_of or args.run
    with open(os.path.join(grouped, "report.json")) as f:
        centers = np.array([g["center"] for g in json.load(f)["groups"]], dtype=float)
    if len(centers) < 2:
        sys.exit("%s: one group, no borders" % grouped)
    if args.cloud:
        dz, same = cloud_grids(args.run, cell, centers)
        print("cloud.ply's median heights on 4 grids of cell %g: neighbouring cells' |dz|" % cell)
        print("%-28s %9s %9s %9s %9s" % ("pairs", "count", "median", "p90", "p99"))
        print("%-28s %s" % ("across borders", quantiles(dz[~same])))
        print("%-28s %s" % ("inside groups", quantiles(dz[same])))
        return
    ys, xs = np.mgrid[0:h, 0:w]
    cx = ox + (xs + 0.5) * cell
    cy = oy - (ys + 0.5) * cell
    d2 = np.stack([(cx - c[0]) ** 2 + (cy - c[1]) ** 2 for c in centers])
    nearest = np.argsort(d2, axis=0)[:2]
    owner = nearest[0]
    first = np.take_along_axis(d2, nearest[:1], 0)[0]
    second = np.take_along_axis(d2, nearest[1:2], 0)[0]
    apart = np.linalg.norm(centers[nearest[0]] - centers[nearest[1]], axis=-1)
    # Distance to the bisector of the two nearest centres, in cells.
    border = (second - first) / (2 * apart) / cell

    k = 15
    padded = np.pad(np.where(empty, np.nan, z), k, constant_values=np.nan)
    low = np.full(z.shape, np.nan)
    for r0 in range(0, h, 64):
        win = sliding_window_view(padded[r0:r0 + 64 + 2 * k], (2 * k + 1, 2 * k + 1))[:, :w]
        # Windows with no filled cell: no low, no open ground there.
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            low[r0:r0 + win.shape[0]] = np.nanpercentile(
                win.reshape(win.shape[0], win.shape[1], -1), 5, axis=2)
    with np.errstate(invalid="ignore"):
        open_ground = (z - low) < 1.0

    dz, same, dist, both_open = [], [], [], []
    for dr, dc in ((0, 1), (1, 0)):
        a = (slice(0, h - dr), slice(0, w - dc))
        b = (slice(dr, h), slice(dc, w))
        ok = ~empty[a] & ~empty[b]
        dz.append(np.abs(z[a] - z[b])[ok])
        same.append((owner[a] == owner[b])[ok])
        dist.append(np.minimum(border[a], border[b])[ok])
        both_open.append((open_ground[a] & open_ground[b])[ok])
    dz, same, dist, both_open = map(np.concatenate, (dz, same, dist, both_open))

    print("DSM steps (cell %g): neighbouring cells' |dz|" % cell)
    print("%-28s %9s %9s %9s %9s" % ("pairs", "count", "median", "p90", "p99"))
    for name, sel in (("", np.ones_like(same)), ("open ground: ", both_open)):
        print("%-28s %s" % (name + "across borders", quantiles(dz[sel & ~same])))
        print("%-28s %s" % (name + "inside groups", quantiles(dz[sel & same])))
        if name:
            continue
        for lo, hi in ((0, 2), (2, 5), (5, 10), (10, 20), (20, None)):
            m = sel & same & (dist >= lo) & ((dist < hi) if hi else True)
            label = "  %g-%s cells from a border" % (lo, hi if hi else "")
            print("%-28s %s" % (label, quantiles(dz[m])))


if __name__ == "__main__":
    main()

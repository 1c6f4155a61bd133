#!/usr/bin/env python3
"""Writes vis.dat for a PMVS folder exported by `sapmvs export --format pmvs`
from a COLMAP model, as CMVS would: each image's K images that share the
most sparse points with it, and turns useVisData on in its option file.
Without it PMVS2 tries every pair of images of a block of a hundred.

    pmvs_vis_from_colmap.py COLMAP_SPARSE_TXT PMVS_DIR [K]

COLMAP_SPARSE_TXT: a folder with images.txt (colmap model_converter
--output_type TXT); PMVS_DIR: the export, whose sapmvs_frame.json lists the
images in the folder's order.
"""
import collections
import json
import os
import sys


def main():
    if len(sys.argv) not in (3, 4):
        sys.exit(__doc__)
    model, pmvs = sys.argv[1], sys.argv[2]
    k = int(sys.argv[3]) if len(sys.argv) == 4 else 10
    with open(os.path.join(pmvs, "sapmvs_frame.json")) as f:
        names = json.load(f)["images"]
    index = {n: i for i, n in enumerate(names)}
    seen = collections.defaultdict(set)  # point id -> PMVS image indices
    with open(os.path.join(model, "images.txt")) as f:
        lines = [l for l in f if not l.startswith("#")]
    for header, points in zip(lines[0::2], lines[1::2]):
        name = header.split()[9]
        if name not in index:
            sys.exit(f"{model}/images.txt: image {name} is not in {pmvs}/sapmvs_frame.json")
        ids = points.split()[2::3]
        for pid in ids:
            if pid != "-1":
                seen[pid].add(index[name])
    shared = [collections.Counter() for _ in names]
    for imgs in seen.values():
        for a in imgs:
            for b in imgs:
                if a != b:
                    shared[a][b] += 1
    text = ["VISDATA", str(len(names))]
    for i, c in enumerate(shared):
        best = [j for j, _ in c.most_common(k)]
        text.append(" ".join(map(str, [i, len(best)] + best)))
    tmp = os.path.join(pmvs, "vis.dat.part")
    with open(tmp, "w") as f:
        f.write("\n".join(text) + "\n")
    os.replace(tmp, os.path.join(pmvs, "vis.dat"))
    option = os.path.join(pmvs, "option")
    with open(option) as f:
        opts = [("useVisData 1" if l.split()[:1] == ["useVisData"] else l.rstrip("\n")) for l in f]
    with open(option + ".part", "w") as f:
        f.write("\n".join(opts) + "\n")
    os.replace(option + ".part", option)
    print(f"{pmvs}/vis.dat: {len(names)} images, up to {k} each")


if __name__ == "__main__":
    main()

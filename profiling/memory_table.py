#!/usr/bin/env python3
"""Per-group memory of `sapmvs run`s: the plan's estimate beside the measured
peak RSS, from each run's report.json. Usage:
  memory_table.py NAME=RUN_DIR [NAME=RUN_DIR ...]
Prints two Markdown tables: per run (its groups' range of estimate / peak - 1)
and per group."""
import json
import statistics
import sys

MiB = 1 << 20


def groups(path):
    report = json.load(open(f"{path}/report.json"))
    rows = []
    for g in report["groups"]:
        est = g.get("memory_estimate_bytes", {})
        meas = g.get("memory_measured_bytes")
        if not meas or "total" not in est:
            continue
        rows.append((g, est["total"], meas))
    return report, rows


def main(args):
    runs = []
    for arg in args:
        name, _, path = arg.partition("=")
        runs.append((name,) + groups(path))
    print("| block | groups | images per group | measured peaks (MiB) | estimate vs peak: "
          "lowest | median | highest |")
    print("|---|---:|---|---|---:|---:|---:|")
    worst = 0.0
    for name, report, rows in runs:
        errs = [total / meas["peak_rss"] - 1 for _, total, meas in rows]
        sizes = [len(g["images"]) for g, _, _ in rows]
        peaks = [meas["peak_rss"] / MiB for _, _, meas in rows]
        worst = max([worst] + [abs(e) for e in errs])
        print(f"| {name} | {len(rows)} | {min(sizes)}–{max(sizes)} | {min(peaks):.0f}–{max(peaks):.0f} "
              f"| {min(errs) * 100:+.0f} % | {statistics.median(errs) * 100:+.0f} % "
              f"| {max(errs) * 100:+.0f} % |")
    print(f"\nlargest |estimate / peak - 1|: {worst * 100:.0f} %\n")
    print("| block | group | images | process before (MiB) | estimate (MiB) | measured peak (MiB) "
          "| device peak (MiB) | estimate vs peak |")
    print("|---|---|---|---|---|---|---|---|")
    for name, report, rows in runs:
        for g, total, meas in rows:
            peak = meas["peak_rss"]
            own = "" if meas.get("peak_is_group_own") else " (process)"
            print(f"| {name} | {g['group']} | {len(g['images'])} | {meas['rss_before'] / MiB:.0f} "
                  f"| {total / MiB:.0f} | {peak / MiB:.0f}{own} | {meas['device_peak'] / MiB:.1f} "
                  f"| {(total / peak - 1) * 100:+.0f} % |")
        print(f"| {name} | run | {report['images']} | | | {report['peak_rss_bytes'] / MiB:.0f} | | |")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    main(sys.argv[1:])

#!/usr/bin/env python3
"""Per-group memory of `sapmvs run`s: the plan's estimate beside the measured
peak RSS, from each run's report.json. Usage:
  memory_table.py NAME=RUN_DIR [NAME=RUN_DIR ...]
Prints a Markdown table; the last column is estimate / measured - 1."""
import json
import sys

MiB = 1 << 20


def main(args):
    print("| block | group | images | process before (MiB) | estimate (MiB) | measured peak (MiB) "
          "| device peak (MiB) | estimate vs peak |")
    print("|---|---|---|---|---|---|---|---|")
    worst = 0.0
    for arg in args:
        name, _, path = arg.partition("=")
        report = json.load(open(f"{path}/report.json"))
        for g in report["groups"]:
            est = g.get("memory_estimate_bytes", {})
            meas = g.get("memory_measured_bytes")
            if not meas:
                continue
            total = est.get("total", est.get("device", 0) + est.get("host", 0))
            peak = meas["peak_rss"]
            err = total / peak - 1
            worst = max(worst, abs(err))
            own = "" if meas.get("peak_is_group_own") else " (process)"
            print(f"| {name} | {g['group']} | {len(g['images'])} | {meas['rss_before'] / MiB:.0f} "
                  f"| {total / MiB:.0f} | {peak / MiB:.0f}{own} | {meas['device_peak'] / MiB:.1f} "
                  f"| {err * 100:+.0f} % |")
        print(f"| {name} | run | {report['images']} | | | {report['peak_rss_bytes'] / MiB:.0f} | | |")
    print(f"\nlargest |estimate / peak - 1|: {worst * 100:.0f} %")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    main(sys.argv[1:])

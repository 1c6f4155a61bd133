#!/bin/bash
# The scaling runs of profiling/results/scale.md: one flight simulated at
# several sizes (same camera, GSD, overlaps and level), each run with
# --memory-budget 4G under /usr/bin/time -v (peak RSS, CPU time). Writes
# WORK/scale.csv (one row per run, what build/profiling/scale_chart draws)
# and keeps each run's report.json, its time -v output and the load before
# and after (uptime) in WORK.
#
#   profiling/scale_runs.sh [WORK]      # default /tmp/sapmvs_scale
#   CSV_ONLY=1 profiling/scale_runs.sh WORK   # the CSV again from WORK's files
#
# The flight: PRESET (default small) at SCALE (default 4: 4000 x 3000
# images, 12 MP) rendered with SUPERSAMPLING rays per pixel side (default 1:
# a quarter of the render time; the run's time and memory do not depend on
# it), cut to SIZES ("images strips images-per-strip", default 20, 60 and
# 200 images). The 1,000-image run of 320 x 240 images:
#   PRESET=large SCALE=1 SUPERSAMPLING=2 SIZES="100 5 20;300 10 30;1000 20 50"
#
# From the checkout, after building build/sapmvs (SAPMVS=... for another).
set -euo pipefail
work=${1:-/tmp/sapmvs_scale}
sapmvs=${SAPMVS:-./build/sapmvs}
mkdir -p "$work"
csv="$work/scale.csv"
preset=${PRESET:-small}
scale=${SCALE:-4}
supersampling=${SUPERSAMPLING:-1}
echo "images,strips,strip_images,groups,merge_tiles,wall_s,seconds_per_image,cpu_seconds_per_image,megapixels,seconds_per_megapixel,points,peak_rss_mib,largest_group_peak_mib,estimate_over_peak_min,estimate_over_peak_max,load_before" > "$csv"
IFS=';' read -r -a sizes <<< "${SIZES:-20 4 5;60 6 10;200 10 20}"
for spec in "${sizes[@]}"; do
  read -r n strips each <<< "$spec"
  block="$work/block_$n"
  run="$work/run_$n"
  if [ -z "${CSV_ONLY:-}" ]; then
    [ -f "$block/block.yaml" ] ||
      "$sapmvs" -q simulate --preset "$preset" --scale "$scale" --supersampling "$supersampling" \
        --strips "$strips" --strip-images "$each" --no-truth-ortho --out "$block"
    rm -rf "$run"
    uptime > "$work/uptime_$n.txt"
    /usr/bin/time -v "$sapmvs" -q run "$block/block.yaml" --out "$run" --memory-budget 4G \
      > "$work/log_$n.txt" 2> "$work/time_$n.txt"
    uptime >> "$work/uptime_$n.txt"
  fi
  python3 - "$run/report.json" "$work/time_$n.txt" "$work/uptime_$n.txt" "$n" "$strips" "$each" \
    >> "$csv" <<'PY'
import json, re, sys
report, timev, uptime, n, strips, each = sys.argv[1:]
r = json.load(open(report))
t = open(timev).read()
def field(name):
    return float(re.search(re.escape(name) + r": ([0-9.]+)", t).group(1))
# The run resets the kernel's high-water mark for each group, which also
# lowers what time -v reports when an earlier stage (the plan) peaked
# higher: report.json's peak is the whole run's.
rss_kib = max(field("Maximum resident set size (kbytes)"), r["peak_rss_bytes"] / 1024)
cpu = field("User time (seconds)") + field("System time (seconds)")
load = re.search(r"load average: ([0-9.]+)", open(uptime).readline()).group(1)
wall = r["total_seconds"]
# Full-resolution megapixels of the block, from its images' headers.
import glob, os, struct
mp = 0
for f in glob.glob(os.path.join(os.path.dirname(report), "..", "block_" + n, "images", "*.png")):
    with open(f, "rb") as png:
        w, h = struct.unpack(">II", png.read(24)[16:24])
    mp += w * h / 1e6
peaks = [g["memory_measured_bytes"]["peak_rss"] for g in r["groups"] if "memory_measured_bytes" in g]
ratios = [g["memory_estimate_bytes"]["total"] / g["memory_measured_bytes"]["peak_rss"] - 1
          for g in r["groups"] if "memory_measured_bytes" in g and "memory_estimate_bytes" in g]
print(f"{n},{strips},{each},{len(r['groups'])},{r['merge']['tiles']},{wall:.1f},"
      f"{wall / int(n):.3f},{cpu / int(n):.3f},{mp:.0f},{wall / mp:.3f},{r['points']},"
      f"{rss_kib / 1024:.0f},{max(peaks) / 2**20:.0f},{min(ratios):+.0%},{max(ratios):+.0%},{load}")
PY
done
cat "$csv"

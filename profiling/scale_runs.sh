#!/bin/bash
# The scaling runs of profiling/results/scale.md: the `large` preset's flight
# at 100, 300 and 1,000 images (same camera, GSD, overlaps and level), each
# simulated, then run with --memory-budget 4G under /usr/bin/time -v (peak
# RSS, CPU time). Writes WORK/scale.csv (one row per run, what
# build/profiling/scale_chart draws) and keeps each run's report.json, its
# time -v output and the load before and after (uptime) in WORK.
#
#   profiling/scale_runs.sh [WORK]      # default /tmp/sapmvs_scale
#   CSV_ONLY=1 profiling/scale_runs.sh WORK   # the CSV again from WORK's files
#
# From the checkout, after building build/sapmvs (SAPMVS=... for another).
set -euo pipefail
work=${1:-/tmp/sapmvs_scale}
sapmvs=${SAPMVS:-./build/sapmvs}
mkdir -p "$work"
csv="$work/scale.csv"
echo "images,strips,strip_images,groups,merge_tiles,wall_s,seconds_per_image,cpu_seconds_per_image,points,peak_rss_mib,load_before" > "$csv"
for spec in "100 5 20" "300 10 30" "1000 20 50"; do
  read -r n strips each <<< "$spec"
  block="$work/block_$n"
  run="$work/run_$n"
  if [ -z "${CSV_ONLY:-}" ]; then
    [ -f "$block/block.yaml" ] ||
      "$sapmvs" -q simulate --preset large --strips "$strips" --strip-images "$each" --out "$block"
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
rss_kib = field("Maximum resident set size (kbytes)")
cpu = field("User time (seconds)") + field("System time (seconds)")
load = re.search(r"load average: ([0-9.]+)", open(uptime).readline()).group(1)
wall = r["total_seconds"]
print(f"{n},{strips},{each},{len(r['groups'])},{r['merge']['tiles']},{wall:.1f},"
      f"{wall / int(n):.3f},{cpu / int(n):.3f},{r['points']},{rss_kib / 1024:.0f},{load}")
PY
done
cat "$csv"

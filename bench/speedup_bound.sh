#!/usr/bin/env bash
# How far dpts-par's 2-thread speedup can go on DEM, from its own stage times: runs it at
# --threads 1 and 2, alternated, RUNS times each, with --report, and `dpts-par --help` (the
# process start-up: the dynamic loader binding GDAL's libraries, before main). Prints the
# medians of each stage's wall time, the measured speedup (wall from outside the process),
# the bound on it were every stage but the start-up and the open perfectly split over 2
# threads (the most a run reading through GDAL could reach), and the part of the 2-thread
# run outside the pieces' stage (start-up, open, count, merge, write, exit).
# Usage: [RUNS=5] [MODE=qem] bench/speedup_bound.sh DEM [KEEP=10]
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${DPTS_BUILD:-$root/build}
dem=${1:?usage: speedup_bound.sh DEM [KEEP percent]}
keep=${2:-10}
runs=${RUNS:-5}
mode=${MODE:-qem}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

for ((r = 0; r < runs; ++r)); do
  /usr/bin/time -f "%e" -o "$tmp/help.$r" "$build/dpts-par" --help > /dev/null
  for t in 1 2; do
    /usr/bin/time -f "%e" -o "$tmp/wall.$t.$r" "$build/dpts-par" --quiet --threads "$t" \
      --algo "$mode" --keep "$keep%" --report "$tmp/report.$t.$r.json" "$dem" "$tmp/out.ply"
  done
done

python3 - "$tmp" "$runs" "$dem" "$mode" "$keep" <<'EOF'
import json, statistics, sys
tmp, runs, dem, mode, keep = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4], sys.argv[5]
med = statistics.median
def num(path):
    with open(path) as f:
        return float(f.read().split()[-1])
start = med(num(f"{tmp}/help.{r}") for r in range(runs))
wall, stages = {}, {}
for t in (1, 2):
    wall[t] = med(num(f"{tmp}/wall.{t}.{r}") for r in range(runs))
    per = {}
    for r in range(runs):
        with open(f"{tmp}/report.{t}.{r}.json") as f:
            for s in json.load(f)["stages"]:
                per.setdefault(s["stage"], []).append(s["wall_s"])
    stages[t] = {k: med(v) for k, v in per.items()}
print(f"# {dem}: {mode} to {keep} %, medians of {runs} alternated runs a thread count")
print("stage,wall_s_1_thread,wall_s_2_threads")
print(f"start-up (--help),{start:.3f},{start:.3f}")
for k in stages[1]:
    print(f"{k},{stages[1][k]:.3f},{stages[2].get(k, float('nan')):.3f}")
print(f"whole (outside),{wall[1]:.3f},{wall[2]:.3f}")
fixed = start + stages[1].get("open", 0)
bound = wall[1] / (fixed + (wall[1] - fixed) / 2)
outside = wall[2] - stages[2].get("simplify", 0)
print(f"speedup measured {wall[1] / wall[2]:.2f}; bound {bound:.2f} (start-up and open "
      f"serial); outside the pieces at 2 threads {outside:.3f} s of {wall[2]:.3f} "
      f"({100 * outside / wall[2]:.0f} %)")
EOF

#!/usr/bin/env bash
# dpts-eval against exact geodesics on the same pairs: for a DEM, each mode and keep, simplifies
# with dpts-par, measures with `dpts-eval --exact` (CGAL's exact geodesics: small DEMs only) and
# with dpts-eval's default (or the options given), both writing --pairs-out, and prints CSV:
# mode,keep,pairs,mean_err_T,max_err_T,mean_err_S,max_err_S,measure_exact,measure,measure_diff
# where err = (GD - exact) / exact per pair on T and on the mesh S, and measure = the paper's
# figure (mean |GD_T - GD_S| / GD_T), with its relative difference from the exact one.
# Usage: bench/eval_accuracy.sh DEM [dpts-eval options, e.g. --points 60 --sets 1 --delta 5]
#   MODES="vp vp-meta" KEEPS="10 50" bench/eval_accuracy.sh ...   (default: every mode, 10 and 50)
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
dem=${1:?usage: eval_accuracy.sh DEM [dpts-eval options]}
shift
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# The exact run takes the options but the Steiner graph's own (--delta, --steiner), which
# dpts-eval refuses with --exact.
args=("$@") exact_args=()
while (($#)); do
  case $1 in
    --delta) shift 2 || { echo "eval_accuracy.sh: --delta needs a value" >&2; exit 2; }; continue ;;
    --delta=* | --steiner) ;;
    *) exact_args+=("$1") ;;
  esac
  shift
done
echo "mode,keep,pairs,mean_err_T,max_err_T,mean_err_S,max_err_S,measure_exact,measure,measure_diff"
for mode in ${MODES:-qem vp vp-meta pld-meta qslim}; do
  for keep in ${KEEPS:-10 50}; do
    "$root/build/dpts-par" --quiet --algo "$mode" --keep "$keep%" "$dem" "$tmp/s.ply"
    "$root/build/dpts-eval" --quiet --exact "${exact_args[@]}" --dem "$dem" --mesh "$tmp/s.ply" \
      --pairs-out "$tmp/exact.csv"
    "$root/build/dpts-eval" --quiet "${args[@]}" --dem "$dem" --mesh "$tmp/s.ply" \
      --pairs-out "$tmp/approx.csv"
    python3 - "$tmp/exact.csv" "$tmp/approx.csv" "$mode" "$keep" <<'EOF'
import csv, sys
def load(path):
    return {(r["set"], r["i"], r["j"]): (float(r["gd_T"]), float(r["gd_S"]))
            for r in csv.DictReader(open(path))}
exact, approx = load(sys.argv[1]), load(sys.argv[2])
keys = [k for k in exact if 0 < exact[k][0] < float("inf") and exact[k][1] < float("inf")]
err_t = [approx[k][0] / exact[k][0] - 1 for k in keys]
err_s = [approx[k][1] / exact[k][1] - 1 for k in keys]
measure = lambda d: sum(abs(d[k][0] - d[k][1]) / d[k][0] for k in keys) / len(keys)
m_exact, m_approx = measure(exact), measure(approx)
print(f"{sys.argv[3]},{sys.argv[4]},{len(keys)},{sum(err_t) / len(keys):.3e},{max(err_t):.3e},"
      f"{sum(err_s) / len(keys):.3e},{max(err_s):.3e},{m_exact:.6g},{m_approx:.6g},"
      f"{m_approx / m_exact - 1:+.2%}")
EOF
  done
done

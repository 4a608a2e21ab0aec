#!/usr/bin/env bash
# Side by side: ericw-tools `vis` and `sightline vis`, same level, same .prt, same
# thread count, runs alternating. Per run: wall s, CPU (user+sys) s, peak RSS MB, and the
# written rows' Σ against the shipped rows with oracle misses (the vis_rows example).
#   scripts/vis_side_by_side.sh LEVEL_DIR PRT_DIR ERICW_VIS RUNS level...
# Needs target/release/sightline and target/release/examples/vis_rows (or the paths in
# $SIGHTLINE and $VIS_ROWS, e.g. under $CARGO_TARGET_DIR).
set -euo pipefail
levels_dir=$1 prt_dir=$2 ericw=$3 runs=$4; shift 4
here=$(cd "$(dirname "$0")/.." && pwd)
sl=${SIGHTLINE:-$here/target/release/sightline}
rows=${VIS_ROWS:-$here/target/release/examples/vis_rows}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
echo "# $(date -u +%FT%TZ) $(nproc) cores; load before: $(cut -d' ' -f1-3 /proc/loadavg)"
printf "level\ttool\tmode\trun\twall_s\tcpu_s\tpeak_MB\t%s\n" "rows"
measure() { # tool mode run level cmd...
  local tool=$1 mode=$2 run=$3 level=$4; shift 4
  /usr/bin/time -f "%e %U %S %M" -o "$work/t" "$@" > "$work/out" 2>&1 || { echo "FAILED: $*"; cat "$work/out"; return 1; }
  read -r wall user sys rss < "$work/t"
  local r; r=$($rows "$work/$level.bsp" "$levels_dir/$level.bsp")
  printf "%s\t%s\t%s\t%s\t%s\t%.2f\t%.1f\t%s\n" "$level" "$tool" "$mode" "$run" "$wall" "$(echo "$user + $sys" | bc)" "$(echo "$rss / 1024" | bc -l)" "$r"
}
for level in "$@"; do
  for run in $(seq 1 "$runs"); do
    for mode in full fast; do
      flag=(); sflag=()
      [ "$mode" = fast ] && flag=(-fast) && sflag=(--fast)
      cp "$levels_dir/$level.bsp" "$prt_dir/$level.prt" "$work/"; chmod u+w "$work/$level.bsp"; rm -f "$work/$level.vis"
      measure ericw "$mode" "$run" "$level" "$ericw" -threads 2 "${flag[@]}" "$work/$level.bsp"
      cp "$levels_dir/$level.bsp" "$work/"; rm -f "$work/$level.vis-state"
      measure sightline "$mode" "$run" "$level" "$sl" vis "$work/$level.bsp" --prt "$work/$level.prt" --threads 2 --in-place --quiet "${sflag[@]}"
    done
  done
done
echo "# load after: $(cut -d' ' -f1-3 /proc/loadavg)"

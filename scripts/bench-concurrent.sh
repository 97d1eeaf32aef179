#!/usr/bin/env bash
# Side-by-side bake timing that survives a noisy machine: runs two cellbake
# binaries at the same time, one worker thread each, so both see the same
# load; prints each one's process CPU, peak RSS, in-thread stage sums (from
# `bake -v`) and the md5 of its cell content hashes (equal rows: equal md5).
#
#   scripts/bench-concurrent.sh BIN_A BIN_B ROUNDS BAKE_ARGS...
#   e.g. scripts/bench-concurrent.sh /tmp/cellbake.base build/runner/cellbake 2 \
#          configs/plant-demo.toml --store plant.store.db \
#          --set samples.initial=centre --set samples.max=1
#
# Needs two free cores. BAKE_ARGS must not set --out, --threads or -v.
set -euo pipefail
if [[ $# -lt 4 ]]; then
  sed -n '2,12p' "$0" >&2
  exit 2
fi
bin_a=$1 bin_b=$2 rounds=$3
shift 3
for b in "$bin_a" "$bin_b"; do
  [[ -x $b ]] || { echo "bench-concurrent: $b is not an executable" >&2; exit 2; }
done
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

stage_sums() {  # the per-cell stage seconds of a `bake -v` log, summed
  python3 - "$1" <<'PY'
import re, sys
text = open(sys.argv[1]).read()
total = {}
for m in re.finditer(r'cell \d+ done in [\d.]+ s \((.*?)\)', text):
    for name, sec in re.findall(r'(\w+) ([\d.]+)', m.group(1)):
        total[name] = total.get(name, 0) + float(sec)
print('  in-thread: ' + ' '.join(f'{k} {v:.1f}' for k, v in total.items()))
PY
}

for ((r = 1; r <= rounds; ++r)); do
  echo "round $r"
  pids=()
  for side in a b; do
    bin=$bin_a
    [[ $side == b ]] && bin=$bin_b
    /usr/bin/time -f "$side: %U s user CPU, %e s wall, %M KB peak RSS" -o "$work/time.$side" \
      "$bin" bake "$@" --threads 1 -v --out "$work/$side.db" >/dev/null 2>"$work/log.$side" &
    pids+=($!)
  done
  for i in 0 1; do
    if ! wait "${pids[$i]}"; then
      side=$([[ $i == 0 ]] && echo a || echo b)
      echo "bench-concurrent: bake $side failed:" >&2
      tail -5 "$work/log.$side" >&2
      exit 1
    fi
  done
  for side in a b; do
    cat "$work/time.$side"
    stage_sums "$work/log.$side"
    echo "  rows md5: $(sqlite3 "$work/$side.db" 'select id, content_hash from cells order by id' | md5sum | cut -d' ' -f1)"
    rm -f "$work/$side.db"
  done
done

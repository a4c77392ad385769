#!/usr/bin/env bash
# Runs every fuzz target (or those named) for RUNS executions each (default 1,000,000), seeding the
# corpus first (seed.py), two targets at a time, and appends libFuzzer's own summary line of each
# run to fuzz/runs.txt. A crash leaves its input in fuzz/artifacts/<target>/ and fails the script.
# Needs the nightly toolchain and cargo-fuzz (`cargo install cargo-fuzz`).
set -euo pipefail
cd "$(dirname "$0")"
RUNS=${RUNS:-1000000}
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=(obj ply stl gltf mesh_detect nifti nrrd metaimage)
python3 seed.py
cargo +nightly fuzz build -O
status=0
run() {
  local t=$1 log=logs/$1.log
  mkdir -p logs
  if cargo +nightly fuzz run -O "$t" -- -runs="$RUNS" -max_len=65536 -rss_limit_mb=2048 -timeout=10 >"$log" 2>&1; then
    echo "$(date -u +%F) $t: $(grep -E '^Done [0-9]+ runs' "$log" | tail -1) (corpus $(ls corpus/$t | wc -l) files)" >>runs.txt
  else
    echo "$(date -u +%F) $t: FAILED, see fuzz/$log and fuzz/artifacts/$t/" >>runs.txt
    return 1
  fi
}
for ((i = 0; i < ${#targets[@]}; i += 2)); do
  run "${targets[i]}" & a=$!
  b=
  if ((i + 1 < ${#targets[@]})); then run "${targets[i + 1]}" & b=$!; fi
  wait $a || status=1
  [ -n "$b" ] && { wait $b || status=1; }
done
tail -n ${#targets[@]} runs.txt
exit $status

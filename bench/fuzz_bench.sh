#!/usr/bin/env bash
# Runs every libFuzzer target (tests/fuzz/) for RUNS executions (default 10 M) from its seed corpus and reports
# executions, coverage (edges, features), speed and findings; writes bench-fuzz.json. Needs the fuzz build:
#   CXX=clang++ cmake -S . -B build-fuzz -DLIGHTFARM_FUZZ=ON -DLIGHTFARM_TESTS=OFF -DLIGHTFARM_BENCH=OFF
#   cmake --build build-fuzz -j2 --target fuzz_wire fuzz_scene_file fuzz_obj fuzz_script
# Usage: bench/fuzz_bench.sh [RUNS] [TARGET...]   (FUZZ_JSON=FILE: write the JSON there instead; MAX_LEN=N: inputs
# of at most N bytes)
# Do not SIGSTOP a run: libFuzzer times each input by the wall clock, so a stopped run reports a timeout.
set -euo pipefail
cd "$(dirname "$0")/.."
# AddressSanitizer's default 256 MB quarantine of freed memory, rescanned by the leak check libFuzzer runs after
# inputs whose mallocs and frees differ, slowed the OBJ target from 17 k to under 2 k executions a second (RSS 1 GB);
# 16 MB still holds recently freed blocks for use-after-free reports.
export ASAN_OPTIONS=${ASAN_OPTIONS:-quarantine_size_mb=16}
runs=${1:-10000000}
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(wire scene_file obj script)
json="${FUZZ_JSON:-bench-fuzz.json}"
echo "{" > "$json"
printf "%-12s %12s %8s %8s %10s %9s %s\n" target executions edges features exec/s seconds findings
first=1
for t in "${targets[@]}"; do
  work=$(mktemp -d)
  artifacts=$(mktemp -d)
  start=$(date +%s)
  set +e
  "build-fuzz/fuzz/fuzz_$t" -runs="$runs" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 ${MAX_LEN:+-max_len=$MAX_LEN} \
    -artifact_prefix="$artifacts/" "$work" "tests/fuzz/corpus/$t" > "$work.log" 2>&1
  rc=$?
  set -e
  secs=$(( $(date +%s) - start ))
  done_line=$(grep -E "^#[0-9]+.*DONE" "$work.log" | tail -1 || true)
  execs=$(grep -oE "stat::number_of_executed_units: [0-9]+" "$work.log" | awk '{print $2}' || echo 0)
  edges=$(sed -nE 's/.*cov: ([0-9]+).*/\1/p' <<< "$done_line")
  features=$(sed -nE 's/.*ft: ([0-9]+).*/\1/p' <<< "$done_line")
  speed=$(sed -nE 's/.*exec\/s: ([0-9]+).*/\1/p' <<< "$done_line")
  findings=$(find "$artifacts" -type f | wc -l)
  [ "$rc" -eq 0 ] || findings=$((findings > 0 ? findings : 1))
  printf "%-12s %12s %8s %8s %10s %9s %s\n" "$t" "${execs:-0}" "${edges:-?}" "${features:-?}" "${speed:-?}" "$secs" "$findings"
  [ $first -eq 1 ] || echo "," >> "$json"
  first=0
  printf '  "%s": {"executions": %s, "edges": %s, "features": %s, "exec_per_second": %s, "seconds": %s, "findings": %s}' \
    "$t" "${execs:-0}" "${edges:-0}" "${features:-0}" "${speed:-0}" "$secs" "$findings" >> "$json"
  [ "$findings" -eq 0 ] || { echo "  findings in $artifacts; log $work.log"; continue; }
  rm -rf "$work" "$work.log" "$artifacts"
done
printf "\n}\n" >> "$json"
echo "wrote $json"

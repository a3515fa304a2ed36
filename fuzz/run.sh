#!/usr/bin/env bash
# Builds the libFuzzer targets (in the "debug" preset's build: clang, ASan +
# UBSan; the "fuzz" build preset builds them alone) and runs
# each for SECONDS / (number of targets), starting from its seed corpus in
# fuzz/corpus/<target>/ (never written: new inputs go to a scratch copy).
# A crash, leak, timeout or sanitizer report stops with a non-zero status
# and leaves the input in build/debug/fuzz/artifacts/.  Prints one line per target:
# executions, coverage (libFuzzer's "cov" edges) and the corpus size.
#   fuzz/run.sh SECONDS [TARGET...]
set -euo pipefail
cd "$(dirname "$0")/.."
total=${1:?usage: fuzz/run.sh SECONDS [TARGET...]}
shift
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
  targets=(octant_text grid_model manifest btree_file packed_leaf lsm_run_list record_schema options
           etree_file layer_table xyz_grid http_request http_exchange rfile)
fi
cmake --preset debug >/dev/null && cmake --build --preset fuzz >/dev/null
out=build/debug/fuzz
per=$(( total / ${#targets[@]} )); [ "$per" -ge 1 ] || per=1
mkdir -p $out/artifacts $out/logs
status=0
for t in "${targets[@]}"; do
  work=$out/work/$t
  rm -rf "$work" && mkdir -p "$work" && cp -r "fuzz/corpus/$t/." "$work/"
  log=$out/logs/$t.log
  if ! ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
       "$out/${t}_fuzz" "$work" -max_total_time="$per" -timeout=10 -rss_limit_mb=2048 \
       -max_len=65536 -artifact_prefix="$out/artifacts/$t-" -print_final_stats=1 >"$log" 2>&1; then
    echo "$t: FAILED (see $log)"; tail -30 "$log"; status=1; continue
  fi
  runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo 0)
  cov=$(grep -o 'cov: [0-9]*' "$log" | tail -1 | grep -o '[0-9]*' || echo 0)
  echo "$t: $runs executions, coverage $cov edges, corpus $(ls "$work" | wc -l) inputs"
done
exit $status

#!/usr/bin/env bash
# Runs every fuzz target of a fuzzing build (-DCONCERT_FUZZ=ON) for a set time and prints, per
# target, executions, coverage and what it found. `make fuzz` calls it; so does CI's short smoke
# (`make fuzz-smoke`: --smoke, the targets marked for it).
#   tests/fuzz/run.sh BUILD_DIR SECONDS [--smoke | TARGET...]
# Environment: FUZZ_SEED (libFuzzer -seed, default 0 = random), FUZZ_RSS_MB (default 2048).
# Each target runs on its corpus (BUILD_DIR/tests/fuzz/corpus/<target>, kept between runs), its
# seeds and the committed regression inputs, with its dictionary. A crash, leak, timeout (10 s on
# one input) or out-of-memory is written to BUILD_DIR/tests/fuzz/artifacts/<target>/ and makes
# the script exit 1 once every target has run. The table is also written to
# BUILD_DIR/tests/fuzz/report.md.
set -uo pipefail

if [ $# -lt 2 ]; then
  echo "usage: $0 BUILD_DIR SECONDS [--smoke | TARGET...]" >&2
  exit 2
fi
build=$(cd "$1" && pwd)
seconds=$2
shift 2
smoke_only=0
if [ "${1:-}" = "--smoke" ]; then
  smoke_only=1
  shift
fi
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
fuzz="$build/tests/fuzz"
list="$fuzz/targets.txt"
[ -f "$list" ] || { echo "run.sh: $list missing: configure with -DCONCERT_FUZZ=ON and build fuzz_all" >&2; exit 2; }

# Symbolized stack traces in the logs.
if [ -z "${ASAN_SYMBOLIZER_PATH:-}" ]; then
  symbolizer=$(command -v llvm-symbolizer-16 || command -v llvm-symbolizer || true)
  [ -n "$symbolizer" ] && export ASAN_SYMBOLIZER_PATH="$symbolizer"
fi

report="$fuzz/report.md"
{
  echo "| target | seconds | executions | exec/s | coverage (edges) | features | corpus | result |"
  echo "|---|---|---|---|---|---|---|---|"
} > "$report"

failed=()
while read -r name binary smoke max_len; do
  [ -n "$name" ] || continue
  if [ $# -gt 0 ] && [[ " $* " != *" $name "* ]]; then continue; fi
  if [ "$smoke_only" -eq 1 ] && [ "$smoke" != 1 ]; then continue; fi
  if [ ! -x "$binary" ]; then
    echo "| $name | 0 | - | - | - | - | - | FAILED: not built ($binary) |" | tee -a "$report"
    failed+=("$name")
    continue
  fi
  corpus="$fuzz/corpus/$name"
  artifacts="$fuzz/artifacts/$name"
  seeds="$fuzz/seeds/$name"
  regressions="$here/regressions/$name"
  log="$fuzz/logs/$name.log"
  mkdir -p "$corpus" "$artifacts" "$(dirname "$log")"
  args=(-max_total_time="$seconds" -rss_limit_mb="${FUZZ_RSS_MB:-2048}" -timeout=10
        -print_final_stats=1 -seed="${FUZZ_SEED:-0}" -artifact_prefix="$artifacts/")
  [ -f "$seeds.dict" ] && args+=(-dict="$seeds.dict")
  [ -n "${max_len:-}" ] && args+=(-max_len="$max_len")
  dirs=("$corpus" "$seeds")
  [ -d "$regressions" ] && dirs+=("$regressions")
  start=$(date +%s)
  "$binary" "${args[@]}" "${dirs[@]}" > "$log" 2>&1
  code=$?
  took=$(( $(date +%s) - start ))
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
  status=$(grep -E '^#[0-9]+.*(cov|DONE)' "$log" | tail -1)
  cov=$(sed -n 's/.* cov: \([0-9]*\).*/\1/p' <<< "$status")
  ft=$(sed -n 's/.* ft: \([0-9]*\).*/\1/p' <<< "$status")
  corp=$(sed -n 's/.* corp: \([0-9]*\).*/\1/p' <<< "$status")
  if [ "$code" -eq 0 ]; then
    result="no crash"
  else
    result="FAILED (exit $code): $(grep -m1 -E 'ERROR: |fuzz check failed|Assertion|runtime error|deadly signal' "$log" | cut -c1-120)"
    failed+=("$name")
  fi
  line="| $name | $took | ${runs:-?} | ${rate:-?} | ${cov:-?} | ${ft:-?} | ${corp:-?} | $result |"
  echo "$line" >> "$report"
  echo "$line"
done < "$list"

if [ ${#failed[@]} -gt 0 ]; then
  echo "run.sh: ${#failed[@]} target(s) failed: ${failed[*]}; logs in $fuzz/logs, inputs in $fuzz/artifacts" >&2
  exit 1
fi
echo "run.sh: every target ran ${seconds} s without a crash (report: $report)"

#!/usr/bin/env bash
# Runs the benchmark programs of the build (targets named bench_*) and writes their current
# figures into docs/benchmarks.md: one section per benchmark with the date, the commit, the
# machine and its load, and what the program printed (a failed run too, with its exit code). A
# benchmark not run this time keeps its section as it was; earlier results are in git history.
#
# Usage: deploy/bench.sh [BUILD_DIR] [BENCH...]
#   BENCH: program names (default: every bench_* program of the build). Arguments for one
#   program: BENCH_ARGS_<name>="..." in the environment, e.g.
#   BENCH_ARGS_bench_drill_mission="--scenario blobs".
# Full output: BUILD_DIR/bench/<name>.out (stdout) and .err (stderr).
set -uo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/.." && pwd)
build=${1:-build}
shift || true
export CONCERT_DOMAIN_ID=${CONCERT_DOMAIN_ID:-49}
doc="$root/docs/benchmarks.md"
outdir="$build/bench"
[ -d "$build" ] || { echo "bench.sh: no build folder '$build' (usage: deploy/bench.sh [BUILD_DIR] [BENCH...])" >&2; exit 2; }
mkdir -p "$outdir"

mapfile -t all < <(find "$build" -type f -executable -name 'bench_*' ! -path '*/CMakeFiles/*' | sort)
[ ${#all[@]} -gt 0 ] || { echo "bench.sh: no bench_* programs under $build (run make build first)" >&2; exit 1; }
benches=()
if [ $# -gt 0 ]; then
  for want in "$@"; do
    found=""
    for b in "${all[@]}"; do [ "$(basename "$b")" = "$want" ] && found=$b; done
    [ -n "$found" ] || { echo "bench.sh: no program '$want' under $build; there are: $(for b in "${all[@]}"; do printf '%s ' "$(basename "$b")"; done)" >&2; exit 2; }
    benches+=("$found")
  done
else
  benches=("${all[@]}")
fi

commit=$(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown)
# (docs/benchmarks.md itself, rewritten by an earlier run, does not count as a change.)
git -C "$root" diff --quiet HEAD -- . ':!docs/benchmarks.md' 2>/dev/null || commit="$commit (with uncommitted changes)"
cpu=$(sed -n 's/^model name[[:space:]]*: //p' /proc/cpuinfo | head -1)
machine="$(nproc) cores ($cpu), $(free -g | awk '/^Mem:/ {print $2}') GiB, $(. /etc/os-release && echo "$PRETTY_NAME"), build type $(sed -n 's/^CMAKE_BUILD_TYPE:STRING=//p' "$build/CMakeCache.txt" 2>/dev/null)"

# Existing sections, kept for the benchmarks not run now.
declare -A kept
if [ -f "$doc" ]; then
  name=""
  while IFS= read -r line; do
    if [[ "$line" =~ ^\<!--\ bench:([A-Za-z0-9_.-]+)\ --\>$ ]]; then name=${BASH_REMATCH[1]}; kept[$name]=""; continue; fi
    if [[ "$line" =~ ^\<!--\ /bench:([A-Za-z0-9_.-]+)\ --\>$ ]]; then name=""; continue; fi
    [ -n "$name" ] && kept[$name]+="$line"$'\n'
  done < "$doc"
fi

failed=()
for b in "${benches[@]}"; do
  name=$(basename "$b")
  var="BENCH_ARGS_${name//[^A-Za-z0-9_]/_}"
  read -r -a args <<< "${!var:-}"
  echo "=== $name ${args[*]:-}"
  load_before=$(cut -d' ' -f1-3 /proc/loadavg)
  start=$(date +%s)
  "$b" "${args[@]}" > "$outdir/$name.out" 2> "$outdir/$name.err"
  code=$?
  took=$(( $(date +%s) - start ))
  load_after=$(cut -d' ' -f1-3 /proc/loadavg)
  cat "$outdir/$name.out"
  [ "$code" -eq 0 ] || { failed+=("$name"); echo "bench.sh: $name exited $code (stderr: $outdir/$name.err)" >&2; }
  section="## $name"$'\n\n'
  section+="- run: $(date -u +%Y-%m-%d) at commit $commit, ${took} s, exit code $code"$'\n'
  section+="- command: \`$name${args[*]:+ ${args[*]}}\`"$'\n'
  section+="- machine: $machine; load average $load_before before, $load_after after"$'\n\n'
  lines=$(wc -l < "$outdir/$name.out")
  if [ "$lines" -gt 80 ]; then
    section+="Its last 80 of $lines lines:"$'\n\n'
  fi
  section+='```'$'\n'"$(tail -n 80 "$outdir/$name.out")"$'\n''```'$'\n'
  kept[$name]=$section
  echo
done

{
  echo "# Benchmarks: current figures"
  echo
  echo "Written by \`make bench\` (deploy/bench.sh): each section is the last run of one benchmark"
  echo "program, with its date, commit, machine and load; earlier results are in git history."
  echo "Run one again with \`make bench BENCHES=\"bench_x\"\` (arguments:"
  echo "\`BENCH_ARGS_bench_x=\"...\"\`). Figures come from a 2-core machine often shared with builds:"
  echo "tails (p95, p99) are dominated by scheduling there; treat them as upper bounds."
  echo
  for name in $(printf '%s\n' "${!kept[@]}" | sort); do
    echo "<!-- bench:$name -->"
    printf '%s' "${kept[$name]}"
    echo "<!-- /bench:$name -->"
    echo
  done
} > "$doc.tmp" && mv "$doc.tmp" "$doc"
echo "bench.sh: wrote $doc"
if [ ${#failed[@]} -gt 0 ]; then
  echo "bench.sh: ${#failed[@]} benchmark(s) failed: ${failed[*]}" >&2
  exit 1
fi

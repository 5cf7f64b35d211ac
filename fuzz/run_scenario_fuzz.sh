#!/usr/bin/env bash
# Runs the scenario loader's fuzz target (fuzz/scenario_fuzz.cc) for SECONDS from a fresh corpus
# seeded from scenarios/ (fuzz/make_scenario_seeds.cc) with fuzz/scenario.dict; ctest's
# scenario_fuzz runs it for 30 s. Exits non-zero on any finding (crash, sanitizer report, leak, an
# input over 1 s, over 2 GB) and when the fuzz tree is not built; a finding is kept as
# FUZZ_DIR/scenario-fuzz-<kind>-<sha1> (replay: FUZZ_DIR/fuzz/scenario_fuzz FILE).
# libFuzzer's 1 s limit is wall-clock time: on a starved machine (other builds on both cores) an
# input of 100 ms can pass it. An input over 1 s is therefore run once more; when it then stays
# under 1 s it is reported as starvation, not a hang, and fuzzing goes on for the time left.
#   fuzz/run_scenario_fuzz.sh FUZZ_DIR [SECONDS]
set -euo pipefail
fuzz_dir=$(realpath -m "$1")
seconds=${2:-30}
source_dir=$(cd "$(dirname "$0")/.." && pwd)
target=$fuzz_dir/fuzz/scenario_fuzz
seeds_tool=$fuzz_dir/fuzz/make_scenario_seeds

if [ ! -x "$target" ] || [ ! -x "$seeds_tool" ]; then
  echo "scenario_fuzz: $target is not built: ctest's fuzz.build_tree builds it, or from $source_dir:" >&2
  echo "  fuzz/build_fuzz_tree.sh $fuzz_dir" >&2
  if [ -f "$fuzz_dir.build.log" ]; then echo "the log of its last build: $fuzz_dir.build.log" >&2; fi
  exit 1
fi
# The sources may have changed since the tree was built: fuzz what is checked out (no-op when current).
cmake --build "$fuzz_dir" -j2 --target scenario_fuzz make_scenario_seeds > "$fuzz_dir.test-build.log" 2>&1 ||
  { cat "$fuzz_dir.test-build.log" >&2; exit 1; }

work=$(mktemp -d "${TMPDIR:-/tmp}/scenario_fuzz.XXXXXX")
trap 'rm -rf "$work"' EXIT
"$seeds_tool" "$source_dir/scenarios" "$work/seeds"
mkdir "$work/corpus"
cd "$work"  # nothing is written, and were it, not into the repository
left=$seconds
while [ "$left" -gt 0 ]; do
  started=$SECONDS
  status=0
  "$target" -max_total_time="$left" -timeout=1 -rss_limit_mb=2048 -print_final_stats=1 \
    -dict="$source_dir/fuzz/scenario.dict" -artifact_prefix="$work/finding-" \
    "$work/corpus" "$work/seeds" > "$work/log" 2>&1 || status=$?
  grep -v -E '^#[0-9]+[[:space:]]+(NEW|REDUCE|pulse)' "$work/log" || true
  [ "$status" -eq 0 ] && exit 0
  finding=$(ls "$work"/finding-* 2>/dev/null | head -n 1)
  if [ -z "$finding" ]; then echo "scenario_fuzz: the fuzzer failed ($status) without a finding" >&2; exit 1; fi
  if [[ "$finding" == */finding-timeout-* ]] &&
     "$target" -timeout=1 -runs=1 "$finding" > "$work/replay" 2>&1; then
    echo "scenario_fuzz: the input over 1 s ran in $(grep -o '[0-9]* ms' "$work/replay" | tail -n 1) on replay:" \
         "the machine was starved, not a hang; fuzzing on" >&2
    rm "$finding"
    left=$((left - (SECONDS - started)))
    continue
  fi
  kept="$fuzz_dir/scenario-fuzz-${finding##*/finding-}"
  cp "$finding" "$kept"
  echo "scenario_fuzz: FINDING, input kept as $kept (replay: $target $kept)" >&2
  exit 1
done

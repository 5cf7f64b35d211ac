#!/usr/bin/env bash
# Configures and builds the clang tree of the libFuzzer targets (the scenario loader's and the wire
# decoder's; docs/hardware.md "Fuzzing", docs/scenarios.md "Fuzzing the loader") in FUZZ_DIR, its
# output in FUZZ_DIR.build.log. ctest's fuzz.build_tree runs it before scenario_fuzz (a fixture), so
# ./setup.sh builds only what the main command needs. Incremental when the tree exists.
#   fuzz/build_fuzz_tree.sh [FUZZ_DIR]    (default build-fuzz beside the sources)
set -uo pipefail
source_dir=$(cd "$(dirname "$0")/.." && pwd)
fuzz_dir=$(realpath -m "${1:-$source_dir/build-fuzz}")
log=$fuzz_dir.build.log
{ CC=clang-14 CXX=clang++-14 cmake -S "$source_dir" -B "$fuzz_dir" -G Ninja -DGRASPBED_FUZZ=ON -DGRASPBED_PYTHON=OFF \
    -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only" &&
  cmake --build "$fuzz_dir" -j2 --target scenario_fuzz make_scenario_seeds decoder_fuzz; } > "$log" 2>&1
status=$?
if [ $status -ne 0 ]; then
  tail -n 40 "$log" >&2
  echo "build_fuzz_tree: the fuzz targets did not build in $fuzz_dir (whole log: $log)" >&2
  exit $status
fi
echo "build_fuzz_tree: built scenario_fuzz, make_scenario_seeds and decoder_fuzz in $fuzz_dir"

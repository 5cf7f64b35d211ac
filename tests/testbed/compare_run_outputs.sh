#!/usr/bin/env bash
# Compares two trees of run outputs (e.g. `graspbed suite scenarios --out A` before a change to the
# run path and `--out B` after): every run's signals.csv, states.csv and config.yaml byte for byte,
# and summary.json less its wall-clock fields (real_time_factor, metrics.wall_s). Exit 0 when all
# are the same, 1 otherwise (naming each file that differs).
#   tests/testbed/compare_run_outputs.sh BEFORE_DIR AFTER_DIR
set -u
before=$1; after=$2; status=0; runs=0
strip='import json,sys
d=json.load(open(sys.argv[1])); d.pop("real_time_factor",None); d.get("metrics",{}).pop("wall_s",None)
print(json.dumps(d,indent=1,sort_keys=True))'
for dir in "$before"/*/; do
  name=$(basename "$dir"); runs=$((runs + 1))
  for file in signals.csv states.csv config.yaml; do
    [ -e "$dir/$file" ] || continue
    cmp -s "$dir/$file" "$after/$name/$file" || { echo "differs: $name/$file"; status=1; }
  done
  diff <(python3 -c "$strip" "$dir/summary.json") <(python3 -c "$strip" "$after/$name/summary.json") > /dev/null ||
    { echo "differs: $name/summary.json"; status=1; }
done
echo "compared $runs runs: $([ $status -eq 0 ] && echo 'all the same' || echo 'differences above')"
exit $status

#!/usr/bin/env bash
# Regenerates every picture the docs and the README show, and the figures their captions quote:
#   docs/img/scenarios/   a still of every shipped scenario at 1.8 s (the README's picture among them)
#   docs/img/side/        the pinch from the side (docs/simulation.md, "The hand in its grasps")
#   docs/img/grasps/      objects held, grasp camera (docs/simulation.md)
#   docs/img/fingertip/   the fingertip camera (docs/simulation.md)
#   docs/img/objects/     each object of the library in the grasp it gets (docs/scenarios.md)
#   docs/img/layout/      the labelled layouts (graspbed sensor layout --picture; docs/sensor.md)
#   docs/img/default_video_strip.png   6 frames of `graspbed run --video` of the default scenario
#   docs/img/getting-started/  the seven plots of the default run (docs/getting-started.md)
#   docs/img/captions.md  for each still: the tick, phase, grip, squeeze, height and loaded units, read
#                         from the signals.csv of a run with the same scenario and overrides
# Needs a build (build/graspbed, or $GRASPBED), python3 and ffmpeg; no display. Takes about 2 minutes on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/../.."
graspbed="${GRASPBED:-build/graspbed}"
runs=$(mktemp -d)
trap 'rm -rf "$runs"' EXIT
captions="$runs/captions.rows"
: > "$captions"
size=(--width 640 --height 480)

# still DIR SCENARIO TIME [render and run options...]: renders SCENARIO at TIME into docs/img/DIR and
# appends its caption figures (from a run with the same --set options) to the captions table.
still() {
  local dir=$1 scenario=$2 at=$3
  shift 3
  local render_only=() sets=()
  while (($#)); do
    case $1 in
      --set) sets+=("$1" "$2"); shift 2 ;;
      *) render_only+=("$1"); shift ;;
    esac
  done
  "$graspbed" render "$scenario" --at "$at" "${size[@]}" "${sets[@]}" "${render_only[@]}" \
    --out "docs/img/$dir" > "$runs/render.log" 2>&1 || { cat "$runs/render.log" >&2; exit 1; }
  # One run per scenario and overrides, shared by its stills. Its exit is 1 where an expectation
  # fails (an object the scenario was not written for).
  local run
  run="$runs/$(printf '%s\n' "$scenario" "${sets[@]}" | md5sum | cut -c1-16)"
  if [ ! -d "$run" ]; then
    local status=0
    "$graspbed" run "$scenario" "${sets[@]}" --no-plots --out "$run" > "$run.log" 2>&1 || status=$?
    [ "$status" -le 1 ] || { cat "$run.log" >&2; exit 1; }
  fi
  local name picture
  name=$(sed -n 's/^scenario \([^,]*\),.*/\1/p' "$run.log" | head -1)
  picture="$dir/$(printf '%s_t%.3fs.png' "$name" "$at")"
  [ -f "docs/img/$picture" ] || { echo "regenerate: $picture was not written" >&2; exit 1; }
  local command="graspbed render $scenario --at $at" word
  for word in "${sets[@]}" "${render_only[@]}"; do
    if [[ $word =~ ^[A-Za-z0-9_./=:,+-]+$ ]]; then command+=" $word"; else command+=" '$word'"; fi
  done
  python3 docs/img/caption_figures.py "$picture" "$run/signals.csv" "$at" "$command" >> "$captions"
}

rm -rf docs/img/scenarios docs/img/side docs/img/grasps docs/img/fingertip docs/img/objects docs/img/layout
mkdir -p docs/img/scenarios docs/img/side docs/img/grasps docs/img/fingertip docs/img/objects docs/img/layout

for scenario in scenarios/*.yaml; do
  still scenarios "$scenario" 1.8 --contact-forces --force-scale 4
done

side=(--view 90,-5,0.3,0.01,0,0.09)
box30=(--set name=box_30mm --set "object.size_m=[0.03,0.05,0.08]")
box70=(--set name=box_70mm --set "object.size_m=[0.07,0.05,0.08]")
sphere45=(--set name=sphere_45mm --set object.shape=sphere --set "object.size_m=[0.045,0,0]")
still side scenarios/default.yaml 0.1 "${side[@]}"
still side scenarios/default.yaml 0.7 "${side[@]}"
still side scenarios/default.yaml 0.7 "${box30[@]}" "${side[@]}"
still side scenarios/default.yaml 0.7 "${box70[@]}" "${side[@]}"
still grasps scenarios/default.yaml 1.8
still grasps scenarios/default.yaml 1.8 "${box30[@]}"
still grasps scenarios/default.yaml 1.8 "${box70[@]}"
still grasps scenarios/pouring_cup.yaml 2.8
still grasps scenarios/default.yaml 1.8 "${sphere45[@]}"
still grasps scenarios/regrasp.yaml 0.6
still grasps scenarios/regrasp.yaml 2.9
still grasps scenarios/tilt_in_grasp.yaml 1.5
still grasps scenarios/tilt_in_grasp.yaml 2.2
still grasps scenarios/ball_rolls.yaml 1.0
still grasps scenarios/ball_rolls.yaml 1.5
still grasps scenarios/wrap_cylinder.yaml 1.8 --set name=wrap_50mm_top --view 0,-89,0.28,0,0,0.05 \
  --contact-forces --force-scale 4
still fingertip scenarios/default.yaml 1.8 --camera fingertip
still fingertip scenarios/default.yaml 1.8 "${box70[@]}" --camera fingertip
still fingertip scenarios/regrasp.yaml 2.9 --camera fingertip

# Each library object in the grasp a scenario naming it gets (lift_can's script: closed at 0.15 s,
# lifted 50 mm from 0.8 s to 1.6 s).
for object in $("$graspbed" objects --json | python3 -c 'import json,sys; [print(o["name"]) for o in json.load(sys.stdin)]'); do
  still objects scenarios/lift_can.yaml 1.8 --set "name=$object" --set "object.name=$object" \
    --contact-forces --force-scale 4
done

for layout in sensor/layouts/default_20.yaml sensor/layouts/paper_3x3.yaml; do
  "$graspbed" sensor layout --layout "$layout" --picture "docs/img/layout/$(basename "$layout" .yaml).png" > /dev/null
done

"$graspbed" run scenarios/default.yaml --no-plots --out "$runs/video" --video > /dev/null
cp "$runs/video/video_strip.png" docs/img/default_video_strip.png
rm -rf docs/img/getting-started
mkdir -p docs/img/getting-started
"$graspbed" run scenarios/default.yaml --out "$runs/plots" > /dev/null
cp "$runs"/plots/*.png docs/img/getting-started/

{
  echo "# Caption figures (generated)"
  echo
  echo "Written by \`docs/img/regenerate.sh\` on $(date -u +%F) at commit $(git rev-parse --short HEAD 2> /dev/null || echo unknown)"
  echo "with \`$graspbed\`; do not edit. For each still: the control tick at or after its instant in the"
  echo "signals.csv of a run with the same scenario and overrides, the controller's phase, the grip it"
  echo "estimates (sum of the units' Fn), the true squeeze of the object, how high the object is lifted,"
  echo "and the units loaded (estimated Fn of at least 0.2 N, in N)."
  echo
  echo "| picture | tick [s] | phase | grip est. [N] | squeeze [N] | lifted [mm] | loaded units (Fn [N]) | command |"
  echo "|---|---|---|---|---|---|---|---|"
  cat "$captions"
} > docs/img/captions.md
echo "regenerate: $(wc -l < "$captions") stills, 2 layouts, the video strip, the default run's plots and docs/img/captions.md written"

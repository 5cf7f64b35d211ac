#!/usr/bin/env bash
# Regenerates the rendered pictures of docs/simulation.md ("Videos") and the README: a still of every
# shipped scenario at 1.8 s (grasp camera, 640 x 480, contact forces) in docs/img/scenarios/, and the
# default scenario's video strip (6 frames of `graspbed run --video`) as docs/img/default_video_strip.png.
# Needs a build (build/graspbed, or $GRASPBED) and ffmpeg; no display. Takes a few minutes.
set -euo pipefail
cd "$(dirname "$0")/../.."
graspbed="${GRASPBED:-build/graspbed}"
out=docs/img/scenarios
rm -rf "$out"
mkdir -p "$out"
for scenario in scenarios/*.yaml; do
  "$graspbed" render "$scenario" --at 1.8 --width 640 --height 480 --contact-forces --force-scale 4 --out "$out"
done
run_dir=$(mktemp -d)
trap 'rm -rf "$run_dir"' EXIT
"$graspbed" run scenarios/default.yaml --no-plots --out "$run_dir" --video > /dev/null
cp "$run_dir/video_strip.png" docs/img/default_video_strip.png

#!/bin/sh
# Drives `graspbed view` with real key presses on the X display it runs under (xvfb-run), as a user's
# keyboard would: xdotool focuses the viewer's window and types into it.
#   view_keys.sh GRASPBED "KEYS" VIEW-ARGUMENTS...
# KEYS: xdotool key names (space, Right, q, ...) and pauses (sleep:SECONDS), in order. Prints the
# viewer's output and exits with its exit code (3 when its window never appeared, 4 when it was still
# open 60 s after the last key: a quit key that did not arrive).
set -u
binary=$1
keys=$2
shift 2
out=$(mktemp)
"$binary" view "$@" >"$out" 2>&1 &
viewer=$!
window=$(timeout 60 xdotool search --sync --name '^graspbed view' | head -n 1)
if [ -z "$window" ]; then
  kill "$viewer" 2>/dev/null
  cat "$out"
  rm -f "$out"
  exit 3
fi
xdotool windowfocus --sync "$window"
sleep 1  # the viewer's first frames (llvmpipe) before the first key, so none arrives unread
for key in $keys; do
  case $key in
    sleep:*) sleep "${key#sleep:}" ;;
    *) xdotool key --window "$window" "$key"; sleep 0.3 ;;
  esac
done
waited=0
while kill -0 "$viewer" 2>/dev/null && [ "$waited" -lt 600 ]; do
  sleep 0.1
  waited=$((waited + 1))
done
if kill -0 "$viewer" 2>/dev/null; then
  kill "$viewer"
  cat "$out"
  rm -f "$out"
  exit 4
fi
wait "$viewer"
status=$?
cat "$out"
rm -f "$out"
exit $status

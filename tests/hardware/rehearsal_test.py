#!/usr/bin/env python3
"""ctest hardware.rehearsal: the bench rehearsal of docs/hardware.md ("The bench workflow", step 2),
as written, N times in a row on a pseudo-terminal:

    graspbed emulate --link L scenarios/default.yaml
    graspbed run scenarios/default.yaml --backend serial --port L --prompt-actions --out OUT

Each time: both exit 0, the host prints PASSED, the device is still connected when the host ends its
session, the device ends because the host stopped the stream (not by its own clock), and the frame
counts agree: every frame the device sent was decoded by the host, but for those still in the
link's buffers when the host closed (at most MAX_IN_FLIGHT, what they hold), and the host's dropped
frames are frames the device could not send (its queue full).

  rehearsal_test.py GRASPBED_BINARY SOURCE_DIR [RUNS]
"""
import json
import os
import pathlib
import subprocess
import sys
import tempfile
import time

BINARY, SOURCE = sys.argv[1], pathlib.Path(sys.argv[2])
RUNS = int(sys.argv[3]) if len(sys.argv) > 3 else 20
SCENARIO = str(SOURCE / "scenarios" / "default.yaml")
# Frames sent that the host never read: the host stops reading when its session ends. On a free
# machine it keeps up and none are left (0 in 20 of 20); when it lags (both cores loaded), the backlog
# is what the link buffers: the device's 64 KiB send queue (hardware/device_emulator.h, out_) and the
# pty's own buffer (measured up to 44 frames), in frames of 20 units of about 175 bytes on the wire
# (docs/protocol.md: body 10 + 8 N, CRC, COBS, delimiter). Loaded, the backlog measured 374 to 419.
FRAME_WIRE_BYTES = 10 + 8 * 20 + 2 + 2 + 1
MAX_IN_FLIGHT = (65536 + 16384) // FRAME_WIRE_BYTES


def rehearse(work, index):
    """One rehearsal; the list of what went wrong (empty when it went well) and its figures."""
    link = work / ("dev%d" % index)
    out = work / ("out%d" % index)
    emulator = subprocess.Popen([BINARY, "emulate", "--link", str(link), SCENARIO, "--json"],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 30.0
        while not os.path.lexists(link):
            if emulator.poll() is not None or time.monotonic() > deadline:
                return ["no link from emulate: " + emulator.stderr.read()], ""
            time.sleep(0.02)
        host = subprocess.run([BINARY, "run", SCENARIO, "--backend", "serial", "--port", str(link),
                               "--prompt-actions", "--no-plots", "--out", str(out)],
                              capture_output=True, text=True, timeout=60)
        device_out, device_err = emulator.communicate(timeout=30)
    finally:
        if emulator.poll() is None:
            emulator.kill()
            emulator.wait()
    problems = []
    if host.returncode != 0 or "PASSED" not in host.stdout:
        problems.append("host: exit %d\n%s%s" % (host.returncode, host.stdout, host.stderr))
    if emulator.returncode != 0:
        problems.append("emulate: exit %d\n%s" % (emulator.returncode, device_err))
    if problems:
        return problems, ""
    bench = json.loads((out / "summary.json").read_text())["bench"]
    device = json.loads(device_out)
    # A pty loses nothing: every frame the device sent was decoded by the host or was still unread in
    # the link's buffers when the host ended. A frame the device took but could not queue (its send
    # queue full: the host lagging) is a gap in the sequence numbers, which the host counts as dropped
    # once it reads a later frame (docs/protocol.md): the host's drops are some of those.
    in_flight = device["frames_sent"] - bench["frames"]
    figures = ("host %d frames + %d dropped, device %d sent + %d overflowed (%d sent and unread at the end), ended by "
               "%s, %d stale periods, %d watchdog trips" % (bench["frames"], bench["dropped"], device["frames_sent"],
                                                            device["frames_overflowed"], in_flight, device["ended_by"],
                                                            bench["stale_periods"], device["watchdog_trips"]))
    if not bench["connected_at_end"]:
        problems.append("the device was gone when the host ended its session")
    if device["ended_by"] != "host_stopped":
        problems.append("the device ended by " + device["ended_by"] + ", not by the host's stop")
    if not 0 <= in_flight <= MAX_IN_FLIGHT:
        problems.append("frames sent and not decoded beyond what the link's buffers hold (%d frames)" % MAX_IN_FLIGHT)
    if bench["dropped"] > device["frames_overflowed"]:
        problems.append("the host counted more frames dropped than the device could not send")
    return problems, figures


def main():
    failed = 0
    with tempfile.TemporaryDirectory() as scratch:
        for index in range(RUNS):
            problems, figures = rehearse(pathlib.Path(scratch), index)
            print("rehearsal %2d: %s%s" % (index + 1, "ok" if not problems else "FAILED", ": " + figures if figures else ""))
            for problem in problems:
                print("    " + problem.replace("\n", "\n    "))
            failed += bool(problems)
    print("%d of %d rehearsals ended well" % (RUNS - failed, RUNS))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())

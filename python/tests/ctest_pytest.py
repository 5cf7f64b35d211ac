#!/usr/bin/env python3
"""pytest as ctest runs it: the same arguments as `python3 -m pytest`, with the skips made visible.

Each skipped test is printed with its reason ("SKIPPED test: reason"), and a run in which nothing
failed but something skipped exits 77, which the ctest entries declare as SKIP_RETURN_CODE: ctest
then shows the entry as skipped instead of passed. A failure keeps pytest's own exit code.
"""
import sys

import pytest

SKIP_RETURN_CODE = 77


class SkipRecorder:
    """Collects the reason of every skipped test (at setup or in its body)."""

    def __init__(self):
        self.skipped = []

    def pytest_runtest_logreport(self, report):
        if not report.skipped:
            return
        reason = report.longrepr[2] if isinstance(report.longrepr, tuple) else str(report.longrepr)
        self.skipped.append((report.nodeid, reason.removeprefix("Skipped: ")))


def main(args):
    recorder = SkipRecorder()
    code = pytest.main(args, plugins=[recorder])
    for test, reason in recorder.skipped:
        print("SKIPPED %s: %s" % (test, reason))
    if code == pytest.ExitCode.OK and recorder.skipped:
        print("%d test(s) skipped: ctest shows this entry as skipped" % len(recorder.skipped))
        return SKIP_RETURN_CODE
    return int(code)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

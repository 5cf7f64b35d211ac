#!/usr/bin/env python3
"""The skip census: every test of a ctest run that judged nothing, with its reason.

  ctest --test-dir build -j2 --output-on-failure --output-junit ctest-junit.xml
  python3 tests/skip_census.py build/ctest-junit.xml

ctest's JUnit report (--output-junit, written in the build directory) marks a test skipped when it
exited with its SKIP_RETURN_CODE (the install and Python entries: 77) or printed GoogleTest's
"[  SKIPPED ]" (GTEST_SKIP). The census prints one line per skipped test with the reason the test
printed, then the count ("skip census: 2 of 541 tests skipped"). Exit 0 once the report is read
(skips are a figure, not a failure); 2 when it cannot be read.
"""
import sys
import xml.etree.ElementTree as ElementTree

# What the project's skips print before their reason: GoogleTest's "file:line: Skipped" line (the
# message follows it), the Python entries' "SKIPPED test: reason" (python/tests/ctest_pytest.py) and
# the install test's own sentence ending "not judged".
GTEST_SKIPPED_LINE = ": Skipped"


def reason_of(output):
    """The reason a skipped test gave, from its captured output."""
    lines = [line.strip() for line in output.splitlines() if line.strip()]
    for i, line in enumerate(lines):
        if line.endswith(GTEST_SKIPPED_LINE) and i + 1 < len(lines):
            return lines[i + 1]
    reasons = [line for line in lines if line.startswith("SKIPPED ") or "not judged" in line]
    if reasons:
        return "; ".join(reasons)
    return lines[-1] if lines else "(no output)"


def main(argv):
    if len(argv) != 2:
        print("usage: skip_census.py CTEST_JUNIT_XML", file=sys.stderr)
        return 2
    try:
        suite = ElementTree.parse(argv[1]).getroot()
    except (OSError, ElementTree.ParseError) as error:
        print("skip census: cannot read %s: %s" % (argv[1], error), file=sys.stderr)
        return 2
    cases = suite.iter("testcase")
    total = 0
    skipped = []
    for case in cases:
        total += 1
        if case.find("skipped") is None:
            continue
        output = case.findtext("system-out") or ""
        skipped.append((case.get("name"), case.find("skipped").get("message", ""), reason_of(output)))
    for name, how, reason in skipped:
        print("skipped: %s (%s): %s" % (name, how, reason))
    print("skip census: %d of %d tests skipped" % (len(skipped), total))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))

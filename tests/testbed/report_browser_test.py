#!/usr/bin/env python3
"""ctest testbed.report_browser: `graspbed suite --report` on three short runs (two controllers, two
sensors, one run failing an expectation on purpose), its page loaded in Debian's chromium, headless.
Checks, in the DOM chromium built after the page's script ran: one row per run with its verdict, the
failed run's expectation in words, the comparison figures, nothing fetched from the network; that
the URL fragment's filters hide what they should (#verdict=failed leaves the failed run,
#controller=open_loop the open-loop run, #verdict=error every row); and takes a screenshot.

  report_browser_test.py GRASPBED_BINARY SOURCE_DIR [--screenshot PATH] [--keep DIR]

--screenshot PATH: where the screenshot goes (docs/img/report.png is one); default a temporary file.
--keep DIR: make the suite there and keep it (for a look at the page); default a temporary folder.
"""
import argparse
import html.parser
import os
import pathlib
import shutil
import subprocess
import sys
import tempfile
import time

parser = argparse.ArgumentParser()
parser.add_argument("binary")
parser.add_argument("source", type=pathlib.Path)
parser.add_argument("--screenshot", type=pathlib.Path)
parser.add_argument("--keep", type=pathlib.Path)
args = parser.parse_args()

# Debian's chromium, installed by setup.sh; as root in a container it needs --no-sandbox.
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
if CHROMIUM is None:
    sys.exit("chromium not found: setup.sh installs Debian's chromium package, which this test loads the report in")
# Loading a local page of a few hundred kB takes well under a second; this bounds a hung browser.
BROWSER_LIMIT_S = 60
failures = []


def check(what, condition, detail=""):
    print("%-6s %s%s" % ("ok" if condition else "FAILED", what, "" if condition else ": " + detail))
    if not condition:
        failures.append(what)


class Dom(html.parser.HTMLParser):
    """The rows of the runs table (attributes of each <tr class="run ...">, the text of its cells),
    the figures, and the addresses the page would fetch."""

    def __init__(self, text):
        super().__init__()
        self.rows, self.figures, self.svgs, self.images, self.remote = [], 0, 0, [], []
        self.html_attributes = {}
        self._row = None
        self.feed(text)

    def handle_starttag(self, tag, attrs):
        attributes = dict(attrs)
        if tag == "html":
            self.html_attributes = attributes
        if tag == "tr" and "run" in (attributes.get("class") or "").split():
            self._row = {"attributes": attributes, "text": ""}
            self.rows.append(self._row)
        if tag == "figure":
            self.figures += 1
        if tag == "svg":
            self.svgs += 1
        if tag == "img":
            self.images.append(attributes.get("src") or "")
        for name in ("src", "href"):
            value = attributes.get(name) or ""
            if tag in ("img", "script", "link", "iframe") and value.startswith(("http:", "https:", "//")):
                self.remote.append(value)

    def handle_endtag(self, tag):
        if tag == "tr":
            self._row = None

    def handle_data(self, data):
        if self._row is not None:
            self._row["text"] += data

    def shown(self):
        return [row for row in self.rows if "hidden" not in row["attributes"]]


def chromium(*arguments, profile):
    command = [CHROMIUM, "--headless", "--disable-gpu", "--no-sandbox", "--user-data-dir=" + str(profile),
               "--no-first-run", "--disable-extensions", *arguments]
    return subprocess.run(command, capture_output=True, text=True, timeout=BROWSER_LIMIT_S)


def dump_dom(page, fragment, profile):
    started = time.monotonic()
    result = chromium("--dump-dom", page.as_uri() + fragment, profile=profile)
    return result.stdout, time.monotonic() - started, result


def make_suite(root):
    """Three short shipped scenarios: ball_rolls and added_mass_step as shipped, and ball_rolls again
    with the open-loop controller, the default sensor and a grip-efficiency limit it cannot meet."""
    scenarios = root / "scenarios"
    scenarios.mkdir(parents=True)
    for name in ("ball_rolls", "added_mass_step"):
        shutil.copy(args.source / "scenarios" / (name + ".yaml"), scenarios)
    text = (args.source / "scenarios" / "ball_rolls.yaml").read_text()
    for old, new in (("name: ball_rolls", "name: ball_rolls_open_loop"),
                     ("controller: {name: grip_slip}", "controller: {name: open_loop}"),
                     ("sensor: {profile: inamp_16bit}", "sensor: {profile: divider_12bit}"),
                     ("max_grip_efficiency: 2.0", "max_grip_efficiency: 0.5")):
        if old not in text:
            sys.exit("scenarios/ball_rolls.yaml no longer has '%s': update this test" % old)
        text = text.replace(old, new)
    (scenarios / "ball_rolls_open_loop.yaml").write_text(text)
    out = root / "suite"
    result = subprocess.run([args.binary, "suite", str(scenarios), "-j", "2", "--out", str(out), "--report"],
                            capture_output=True, text=True)
    print(result.stdout, end="")
    check("graspbed suite --report exits 1 (one run fails on purpose)", result.returncode == 1,
          "exit %d: %s" % (result.returncode, result.stderr.strip()))
    check("it names the report it wrote", "report: %s/report.html (suite, 3 runs" % out in result.stdout,
          result.stdout)
    return out / "report.html"


def run(root):
    page = make_suite(root)
    if not page.is_file():
        sys.exit("no report.html written")
    source = page.read_text()
    check("the page is self-contained (no address it would fetch)", not Dom(source).remote, str(Dom(source).remote))
    profile = root / "chromium-profile"

    text, seconds, result = dump_dom(page, "", profile)
    dom = Dom(text)
    check("chromium loads the page", len(dom.rows) > 0, "no rows in the DOM; stderr: " + result.stderr[-2000:])
    print("       loaded in %.2f s (browser start included); the script ran at %s ms" %
          (seconds, dom.html_attributes.get("data-ready-ms")))
    check("its script ran", "data-ready-ms" in dom.html_attributes, "no data-ready-ms on <html>")
    check("one row per run, all shown", len(dom.rows) == 3 and len(dom.shown()) == 3,
          "%d rows, %d shown" % (len(dom.rows), len(dom.shown())))
    verdicts = sorted(row["attributes"].get("data-verdict") for row in dom.rows)
    check("each run's verdict", verdicts == ["failed", "passed", "passed"], str(verdicts))
    failed = [row for row in dom.rows if row["attributes"].get("data-verdict") == "failed"]
    check("the failed run's first failed expectation in words",
          failed and "max_grip_efficiency: got" in failed[0]["text"] and "limit <= 0.5" in failed[0]["text"],
          failed[0]["text"] if failed else "no failed row")
    check("the comparison figures (runs per verdict, peak grip, slip)", dom.figures >= 3 and dom.svgs >= 3,
          "%d figures, %d svg" % (dom.figures, dom.svgs))
    check("each row links its run's plots", all("grip" in row["text"] and "folder" in row["text"] for row in dom.rows),
          str([row["text"] for row in dom.rows]))

    for fragment, expected in (("#verdict=failed", ["ball_rolls_open_loop"]),
                               ("#controller=open_loop", ["ball_rolls_open_loop"]),
                               ("#sensor=inamp_16bit/paper&verdict=passed", ["added_mass_step", "ball_rolls"]),
                               ("#verdict=error", [])):
        dom = Dom(dump_dom(page, fragment, profile)[0])
        shown = sorted(row["attributes"].get("data-scenario") for row in dom.shown())
        check("%s shows %s and hides the rest" % (fragment, expected or "nothing"),
              len(dom.rows) == 3 and shown == expected, "%d rows, shown %s" % (len(dom.rows), shown))

    screenshot = args.screenshot or root / "report.png"
    screenshot.parent.mkdir(parents=True, exist_ok=True)
    result = chromium("--screenshot=" + str(screenshot.resolve()), "--window-size=1600,1000",
                      "--hide-scrollbars", page.as_uri(), profile=profile)
    check("a screenshot", screenshot.is_file() and screenshot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n",
          result.stderr[-2000:])


if args.keep:
    shutil.rmtree(args.keep, ignore_errors=True)
    run(args.keep)
else:
    with tempfile.TemporaryDirectory() as scratch:
        run(pathlib.Path(scratch))
if failures:
    sys.exit("%d check(s) failed: %s" % (len(failures), "; ".join(failures)))
print("all checks passed")

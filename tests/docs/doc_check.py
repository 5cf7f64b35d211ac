#!/usr/bin/env python3
"""Checks README.md and docs/ against the build (ctest: docs.links, docs.config_reference_tables,
docs.commands; README.md, "Checking the docs", says how a doc marks them).

links      every relative link and image resolves to a file, every `#anchor` to a heading (GitHub's
           slugs), and every section named in prose as `FILE.md, "Heading"` to a heading of FILE
tables     every table between `<!-- config-reference PATH -->` and `<!-- /config-reference -->`
           equals what `graspbed config-reference PATH` prints
commands   every ```sh block right after a `<!-- doc-check -->` line (or `<!-- doc-check: exit N -->`)
           runs with bash -e -o pipefail and exits 0 (or N); a ```python block runs with
           /usr/bin/python3 and PYTHONPATH=build/python, a ```cpp block compiles with g++ -std=c++20
           -fsyntax-only -Wall -Werror against the source tree's headers. The blocks of one file run in order in
           one scratch directory that looks like a checkout after ./setup.sh: a symlink for each
           top-level entry of the source tree and `build` pointing at the build tree under test, whose
           directory is also first on PATH (so `graspbed` is the build's). Each block has
           --timeout seconds; whatever it left running is killed when it ends.

Usage: doc_check.py links|tables|commands --source DIR [--build DIR] [--file NAME ...]
       doc_check.py tables --write --source DIR --build DIR    (regenerates the tables in place)
Exit 0 when every check passes, 1 when one fails (each failure on its own line as FILE:LINE: ...),
2 on bad usage.
"""

import argparse
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

FENCE = re.compile(r"^ {0,3}(`{3,}|~{3,})\s*([\w+-]*)")
MARKER = re.compile(r"^<!--\s*doc-check(?::\s*exit\s+(\d+))?\s*-->\s*$")
ANY_MARKER = re.compile(r"^<!--\s*doc-check\b")
BOLD_LEAD = re.compile(r"^\s*(?:[-*]\s+|\d+\.\s+)?\*\*(.+?)\*\*")
HEADING = re.compile(r"^ {0,3}(#{1,6})\s+(.*?)\s*#*\s*$")
LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
# `docs/simulation.md, "Videos" and "The viewer"`; `scenarios.md, "A", "B"`
SECTION_REF = re.compile(r"([\w./-]+\.md)(?:'s)?,\s+((?:\"[^\"\n]+\"(?:,\s*|\s+and\s+|\s+or\s+)?)+)")
QUOTED = re.compile(r"\"([^\"\n]+)\"")
TABLE_OPEN = re.compile(r"^<!-- config-reference (\S+) -->$")
TABLE_CLOSE = "<!-- /config-reference -->"


def doc_files(source, only):
    files = [source / "README.md"] + sorted((source / "docs").rglob("*.md"))
    if only:
        files = [f for f in files if f.name in only or str(f.relative_to(source)) in only]
    return files


def rel(source, path):
    return str(path.relative_to(source))


def prose_lines(text):
    """(line number, line) of the lines outside fenced code blocks."""
    fence = None
    for number, line in enumerate(text.split("\n"), 1):
        match = FENCE.match(line)
        if fence is None and match:
            fence = match.group(1)
            continue
        if fence is not None:
            if line.strip().startswith(fence) and line.strip().strip(fence[0]) == "":
                fence = None
            continue
        yield number, line


def blank_code_spans(line):
    """`line` with its inline code spans blanked (a `[x](y)` in code is no link)."""
    return re.sub(r"(`+)(.+?)\1", lambda m: " " * len(m.group(0)), line)


def plain(markdown):
    """`markdown` as read: a link's or image's text kept, HTML tags and code ticks dropped."""
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", markdown)
    return re.sub(r"<[^>]+>", "", text).replace("`", "")


def github_slug(heading):
    """The anchor GitHub gives a heading: its plain text in lower case, punctuation other than - and
    _ removed, spaces to hyphens."""
    return re.sub(r"[^\w\- ]", "", plain(heading).lower(), flags=re.UNICODE).replace(" ", "-")


def headings(path):
    """The plain text of each section name of `path` (its headings and the bold words that open a
    paragraph or a list item, "**The time step** is 1 ms") and the set of its GitHub anchors."""
    texts, anchors, seen = [], set(), {}
    for _, line in prose_lines(path.read_text()):
        bold = BOLD_LEAD.match(line)
        if bold:
            texts.append(plain(bold.group(1)))
        match = HEADING.match(line)
        if not match:
            continue
        text = match.group(2)
        texts.append(plain(text).replace("*", ""))
        slug = github_slug(text)
        count = seen.get(slug, 0)
        seen[slug] = count + 1
        anchors.add(slug if count == 0 else f"{slug}-{count}")
    return texts, anchors


def resolve_doc(source, doc, name):
    """The file a prose reference `name` ("docs/x.md", "x.md", "README.md") means, or None."""
    for base in (doc.parent, source, source / "docs"):
        candidate = (base / name).resolve()
        if candidate.is_file():
            return candidate
    return None


def check_links(source, files):
    failures = []
    heading_cache = {}

    def heads(path):
        if path not in heading_cache:
            heading_cache[path] = headings(path)
        return heading_cache[path]

    for doc in files:
        for number, line in prose_lines(doc.read_text()):
            where = f"{rel(source, doc)}:{number}"
            for match in LINK.finditer(blank_code_spans(line)):
                target = match.group(1)
                if re.match(r"^[a-z][a-z0-9+.-]*:", target):  # http:, https:, mailto:
                    continue
                path_part, _, anchor = target.partition("#")
                path = (doc.parent / path_part).resolve() if path_part else doc
                if not path.exists():
                    failures.append(f"{where}: link {target}: no such file {path_part}")
                    continue
                if anchor:
                    if path.suffix != ".md":
                        failures.append(f"{where}: link {target}: an anchor into a file that is not Markdown")
                    elif anchor not in heads(path)[1]:
                        failures.append(f"{where}: link {target}: no heading with anchor #{anchor} in {path.name}")
            code = blank_code_spans(line)
            for match in SECTION_REF.finditer(line):
                if code[match.start()] == " " and line[match.start()] != " ":  # inside `code`
                    continue
                target = resolve_doc(source, doc, match.group(1))
                if target is None:
                    if "/" in match.group(1) or match.group(1) == "README.md":
                        failures.append(f"{where}: {match.group(1)}: no such file")
                    continue
                texts = heads(target)[0]
                for quoted in QUOTED.findall(match.group(2)):
                    wanted = quoted.replace("`", "").lower()
                    if not any(t.lower().startswith(wanted) for t in texts):
                        failures.append(f"{where}: {match.group(1)}, \"{quoted}\": no such section in "
                                        f"{rel(source, target)}")
    return failures


def table_blocks(doc):
    lines = doc.read_text().split("\n")
    index = 0
    while index < len(lines):
        match = TABLE_OPEN.match(lines[index])
        if match:
            end = index + 1
            while end < len(lines) and lines[end] != TABLE_CLOSE:
                end += 1
            yield index + 1, match.group(1), "\n".join(lines[index + 1:end]) + "\n", end < len(lines)
            index = end
        index += 1


def check_tables(source, build, files, write=False):
    failures, printed = [], {}
    binary = build / "graspbed"
    for doc in files:
        if write:
            failures += write_tables(source, binary, doc)
            continue
        for number, path, block, closed in table_blocks(doc):
            where = f"{rel(source, doc)}:{number}"
            if not closed:
                failures.append(f"{where}: config-reference {path}: no {TABLE_CLOSE} after it")
                continue
            if path not in printed:
                result = subprocess.run([str(binary), "config-reference", path], capture_output=True, text=True)
                printed[path] = result.stdout if result.returncode == 0 else None
                if result.returncode != 0:
                    failures.append(f"{where}: graspbed config-reference {path} exits {result.returncode}: "
                                    f"{result.stderr.strip()}")
            if printed[path] is not None and block != printed[path]:
                wrong = [line for line in block.split("\n") if line and line not in printed[path]]
                failures.append(f"{where}: the table of {path} differs from `graspbed config-reference {path}`"
                                f" (regenerate it); first row that differs: {wrong[0] if wrong else '(rows missing)'}")
    return failures


def write_tables(source, binary, doc):
    """Replaces each config-reference block of `doc` by what `graspbed config-reference` prints."""
    lines, out, failures, index = doc.read_text().split("\n"), [], [], 0
    while index < len(lines):
        out.append(lines[index])
        match = TABLE_OPEN.match(lines[index])
        if match:
            result = subprocess.run([str(binary), "config-reference", match.group(1)], capture_output=True,
                                    text=True)
            end = lines.index(TABLE_CLOSE, index + 1) if TABLE_CLOSE in lines[index + 1:] else None
            if result.returncode != 0 or end is None:
                failures.append(f"{rel(source, doc)}:{index + 1}: cannot regenerate {match.group(1)}")
            else:
                out += result.stdout.rstrip("\n").split("\n")
                index = end
                continue
        index += 1
    doc.write_text("\n".join(out))
    return failures


def as_here_document(command, code):
    """`command` reading `code` on its standard input, as a bash block (the code quoted verbatim)."""
    return f"{command} <<'DOC_CHECK_BLOCK'\n{code}DOC_CHECK_BLOCK\n"


# How a marked block runs, by its fence's language: a shell block as it is; a Python block with
# Debian's interpreter and the build tree's module (the one the docs tell users to use); a C++ block
# compiled (not linked) against the controller API's headers, which the install ships as they are in
# the source tree.
RUNNERS = {
    "sh": lambda code: code,
    "python": lambda code: as_here_document("PYTHONPATH=build/python /usr/bin/python3 -", code),
    "cpp": lambda code: as_here_document("g++ -std=c++20 -fsyntax-only -Wall -Werror -I. -x c++ -", code),
}


def marked_blocks(doc):
    """(line, expected exit, code) of each marked block; a marker not followed by a sh fence is an error."""
    lines = doc.read_text().split("\n")
    blocks, errors = [], []
    for index, line in enumerate(lines):
        if not ANY_MARKER.match(line):
            continue
        match = MARKER.match(line)
        fence = FENCE.match(lines[index + 1]) if index + 1 < len(lines) else None
        if not match:
            errors.append((index + 1, f"malformed marker {line.strip()!r} (`<!-- doc-check -->` or "
                                      "`<!-- doc-check: exit N -->`)"))
            continue
        if not fence or fence.group(2) not in RUNNERS:
            errors.append((index + 1, "a doc-check marker must stand right before a ```sh, ```python or ```cpp fence"))
            continue
        end = index + 2
        while end < len(lines) and not lines[end].strip().startswith(fence.group(1)):
            end += 1
        code = "\n".join(lines[index + 2:end]) + "\n"
        blocks.append((index + 2, int(match.group(1) or 0), RUNNERS[fence.group(2)](code)))
    return blocks, errors


def make_scratch(source, build, root, name):
    scratch = root / name
    scratch.mkdir()
    for entry in source.iterdir():
        if entry.name.startswith(".") or entry.name.startswith("build") or entry.name == "out":
            continue
        (scratch / entry.name).symlink_to(entry)
    (scratch / "build").symlink_to(build)
    return scratch


def run_block(code, scratch, env, timeout):
    process = subprocess.Popen(["bash", "-e", "-o", "pipefail", "-c", code], cwd=scratch, env=env,
                               stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                               start_new_session=True)
    try:
        output, _ = process.communicate(timeout=timeout)
        status = process.returncode
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGKILL)
        output, _ = process.communicate()
        status = None
    try:  # whatever the block left in the background
        os.killpg(process.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    return status, output


def check_commands(source, build, files, timeout, keep):
    failures = []
    root = Path(tempfile.mkdtemp(prefix="graspbed-doc-check-"))
    env = dict(os.environ, PATH=f"{build}{os.pathsep}{os.environ.get('PATH', '')}")
    total_start = time.monotonic()
    try:
        for doc in files:
            blocks, errors = marked_blocks(doc)
            failures += [f"{rel(source, doc)}:{line}: {message}" for line, message in errors]
            if not blocks:
                continue
            scratch = make_scratch(source, build, root, rel(source, doc).replace("/", "_"))
            for line, expected, code in blocks:
                where = f"{rel(source, doc)}:{line}"
                start = time.monotonic()
                status, output = run_block(code, scratch, env, timeout)
                seconds = time.monotonic() - start
                print(f"{where}: exit {status} in {seconds:.1f} s (expected {expected})", flush=True)
                if status != expected:
                    said = "timed out after %d s" % timeout if status is None else f"exit {status}"
                    tail = "\n".join("    " + l for l in output.rstrip().split("\n")[-15:])
                    shown = code.rstrip().split("\n")
                    if len(shown) > 6:
                        shown = shown[:2] + ["..."] + shown[-3:]
                    failures.append(f"{where}: {said}, the doc says exit {expected}:\n    $ "
                                    + "\n    $ ".join(shown) + "\n" + tail)
    finally:
        print(f"commands: {time.monotonic() - total_start:.1f} s", flush=True)
        if keep:
            print(f"scratch directories kept in {root}")
        else:
            shutil.rmtree(root, ignore_errors=True)
    return failures


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("check", choices=["links", "tables", "commands"])
    parser.add_argument("--source", required=True, type=Path, help="the source tree (README.md, docs/)")
    parser.add_argument("--build", type=Path, help="the build tree (its graspbed); tables and commands")
    parser.add_argument("--file", action="append", default=[], help="only this doc (name or path); repeatable")
    parser.add_argument("--timeout", type=float, default=180, help="seconds per command block")
    parser.add_argument("--keep", action="store_true", help="keep the scratch directories")
    parser.add_argument("--write", action="store_true",
                        help="tables: rewrite the docs' tables from `graspbed config-reference`")
    args = parser.parse_args()
    source = args.source.resolve()
    if args.check != "links" and (args.build is None or not (args.build / "graspbed").is_file()):
        parser.error("--build must name a build tree with a graspbed binary")
    build = args.build.resolve() if args.build else None
    files = doc_files(source, args.file)
    if not files:
        parser.error("no doc matches --file")
    if args.check == "links":
        failures = check_links(source, files)
    elif args.check == "tables":
        failures = check_tables(source, build, files, args.write)
    else:
        failures = check_commands(source, build, files, args.timeout, args.keep)
    for failure in failures:
        print(failure)
    print(f"{args.check}: {len(files)} files, {len(failures)} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""Checks what `softbake compare` writes for CI, and the report of `softbake run --report`, as
CI's tools and a person's browser read them.

  check_report.py junit FILE TESTS FAILURES
      FILE parses as XML (Python's xml.etree), is JUnit's <testsuites>/<testsuite>/<testcase>, and
      has TESTS test cases of which FAILURES hold a <failure> with a message, its counts in the
      attributes agreeing.
  check_report.py browser FOLDER ROWS SCREENSHOT
      Debian's chromium opens FOLDER/index.html from disk, headless, with the network off (in a
      network namespace of its own where unshare can make one, else with every host unresolvable
      and a proxy that goes nowhere), and dumps the DOM its script leaves: one row per item, ROWS of
      them, failures first, then warnings, then passes; every <img> loaded. The page names no
      address on the network. Then a screenshot of the page goes to SCREENSHOT.
  check_report.py bake FOLDER FRAMES SCREENSHOT
      The same for the bake report of `softbake run --report`: chromium opens it offline and its
      DOM shows the script ran, the flipbook's slider spans FRAMES frames, the frame's numbers
      are beside it, five plots are drawn, and every <img> loaded (the flipbook's frame, when the
      run rendered PNG frames). No network address; a screenshot.

Exit 0 when all holds; otherwise 1 with each problem on a line. Python's standard library only.
"""

import html.parser
import os
import re
import shutil
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ElementTree


def check_junit(path, tests, failures):
    problems = []
    root = ElementTree.parse(path).getroot()
    if root.tag != "testsuites":
        return [f"{path}: the root is <{root.tag}>, not <testsuites>"]
    cases = root.findall("./testsuite/testcase")
    failed = [case for case in cases if case.find("failure") is not None]
    if len(cases) != tests:
        problems.append(f"{path}: {len(cases)} test cases, expected {tests}")
    if len(failed) != failures:
        problems.append(f"{path}: {len(failed)} failures, expected {failures}")
    for element in [root] + root.findall("testsuite"):
        for key, count in (("tests", len(cases)), ("failures", len(failed))):
            if element.get(key) != str(count):
                problems.append(f"{path}: <{element.tag}> says {key}={element.get(key)}, has {count}")
    for case in failed:
        if not case.find("failure").get("message"):
            problems.append(f"{path}: the failure of {case.get('name')} has no message")
        if not case.get("name") or not case.get("classname"):
            problems.append(f"{path}: a test case without name or classname")
    return problems


class ReportDom(html.parser.HTMLParser):
    """The rows (their verdicts and names) and the images of a report's DOM."""

    def __init__(self):
        super().__init__()
        self.rows, self.images = [], []

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if tag == "tr" and "item" in (attrs.get("class") or "").split():
            self.rows.append((attrs.get("data-verdict"), attrs.get("data-name")))
        if tag == "img":
            self.images.append((attrs.get("src"), attrs.get("data-state")))


def chromium(arguments):
    """chromium with `arguments`, the network off; its stdout."""
    command = ["chromium", "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
               "--virtual-time-budget=5000", "--host-resolver-rules=MAP * ~NOTFOUND",
               "--proxy-server=127.0.0.1:9"] + arguments
    if shutil.which("unshare") and subprocess.run(["unshare", "-n", "true"],
                                                  capture_output=True).returncode == 0:
        command = ["unshare", "-n"] + command
    with tempfile.TemporaryDirectory() as profile:
        result = subprocess.run(command + [f"--user-data-dir={profile}"], capture_output=True,
                                text=True, timeout=120, env=dict(os.environ, HOME=profile))
    if result.returncode != 0:
        sys.exit(f"chromium failed ({result.returncode}): {result.stderr[-2000:]}")
    return result.stdout


class BakeReportDom(html.parser.HTMLParser):
    """What the bake report's script left: the flipbook, its numbers, the plots, the images."""

    def __init__(self):
        super().__init__()
        self.ready, self.slider_max, self.numbers, self.plots, self.images = None, None, 0, 0, []
        self.in_numbers = False

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if tag == "body":
            self.ready = attrs.get("data-ready")
        if tag == "input" and attrs.get("id") == "flip-slider":
            self.slider_max = attrs.get("max")
        if tag == "table" and attrs.get("id") == "flip-numbers":
            self.in_numbers = True
        if tag == "tr" and self.in_numbers:
            self.numbers += 1
        if tag == "figure" and "plot" in (attrs.get("class") or "").split():
            self.plots += 1
        if tag == "img":
            self.images.append((attrs.get("src"), attrs.get("data-state")))

    def handle_endtag(self, tag):
        if tag == "table":
            self.in_numbers = False


def network_addresses(page):
    """Problems: addresses on the network `page` names. The SVG namespace is a name, not a
    request."""
    text = open(page, encoding="utf-8").read()
    addresses = [a for a in re.findall(r"(?:https?|ftp)://[^\s\"'<>)]+", text)
                 if a != "http://www.w3.org/2000/svg"]
    return [f"{page} names addresses on the network: {addresses[:3]}"] if addresses else []


def screenshot_problems(page, screenshot):
    os.makedirs(os.path.dirname(os.path.abspath(screenshot)), exist_ok=True)
    chromium([f"--screenshot={os.path.abspath(screenshot)}", "--window-size=1280,1600",
              "file://" + page])
    return [] if os.path.getsize(screenshot) else [f"{screenshot}: empty screenshot"]


def check_bake(folder, frames, screenshot):
    page = os.path.abspath(os.path.join(folder, "index.html"))
    problems = network_addresses(page)
    dom = BakeReportDom()
    dom.feed(chromium(["--dump-dom", "file://" + page]))
    if dom.ready != "true":
        problems.append("the page's script did not run to its end (no data-ready on <body>)")
    if dom.slider_max != str(frames - 1):
        problems.append(f"the flipbook's slider ends at {dom.slider_max}, expected {frames - 1}")
    if dom.numbers < 6:
        problems.append(f"{dom.numbers} rows of numbers beside the flipbook, expected 6 or more")
    if dom.plots != 5:
        problems.append(f"{dom.plots} plots, expected 5")
    for source, state in dom.images:
        if state != "loaded":
            problems.append(f"image {source} did not load (data-state={state})")
    return problems + screenshot_problems(page, screenshot)


def check_browser(folder, rows, screenshot):
    page = os.path.abspath(os.path.join(folder, "index.html"))
    problems = network_addresses(page)
    dom = ReportDom()
    dom.feed(chromium(["--dump-dom", "file://" + page]))
    if len(dom.rows) != rows:
        problems.append(f"{len(dom.rows)} rows, expected {rows}: {dom.rows}")
    rank = {"fail": 0, "warn": 1, "pass": 2}
    verdicts = [rank.get(verdict, 9) for verdict, _ in dom.rows]
    if verdicts != sorted(verdicts) or 9 in verdicts:
        problems.append(f"rows not failures first: {dom.rows}")
    if not dom.images:
        problems.append("no images")
    for source, state in dom.images:
        if state != "loaded":
            problems.append(f"image {source} did not load (data-state={state})")
    return problems + screenshot_problems(page, screenshot)


def main():
    if len(sys.argv) == 5 and sys.argv[1] == "junit":
        problems = check_junit(sys.argv[2], int(sys.argv[3]), int(sys.argv[4]))
    elif len(sys.argv) == 5 and sys.argv[1] == "browser":
        problems = check_browser(sys.argv[2], int(sys.argv[3]), sys.argv[4])
    elif len(sys.argv) == 5 and sys.argv[1] == "bake":
        problems = check_bake(sys.argv[2], int(sys.argv[3]), sys.argv[4])
    else:
        sys.exit(__doc__)
    for problem in problems:
        print(problem)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""report.html opened in headless Chromium (Debian's chromium), as a person would open it.

For runs of several kinds (a schedule with cutting physics, an inch program on the dexel
stock, a program that changes tools) and for a batch with a failing job, checks that
- the page draws with no script error and no console message at all,
- every plot is drawn (painted pixels) and the 3D view is drawn (non-background pixels read
  back from WebGL), and a screenshot is not blank,
- every number on the page equals summary.json's (data-value exactly; the shown text to its
  four significant digits) and the key figures are there,
- report.html#step=N selects step N with its line of G-code, as a click on a plot does,
- the batch page has one row per job, links to the jobs' reports and the failed job's error.

usage: ReportBrowser.py ENGAGE DATA_DIR SOURCE_DIR OUT_DIR   (exit 77: no chromium, skipped)
"""
import html.parser
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile

ENGAGE, DATA, SOURCE, OUT = sys.argv[1:5]
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
if not CHROMIUM:
    print("chromium not installed (apt-get install chromium): skipped")
    sys.exit(77)

failures = []


def check(ok, what):
    if not ok:
        failures.append(what)
        print("FAIL:", what)


def run(args, status=0):
    p = subprocess.run([ENGAGE] + args + ["--quiet"], capture_output=True, text=True)
    if p.returncode != status:
        raise SystemExit(f"engage {' '.join(args)} exited {p.returncode}: {p.stderr}")
    return p.stdout


def chromium(url, extra):
    profile = tempfile.mkdtemp(prefix="engage-chromium-")
    try:
        return subprocess.run(
            [CHROMIUM, "--headless", "--no-sandbox", "--disable-dev-shm-usage",
             "--enable-unsafe-swiftshader", "--use-angle=swiftshader",
             "--user-data-dir=" + profile, "--enable-logging=stderr", "--v=0",
             "--window-size=1400,1800", "--virtual-time-budget=8000"] + extra + [url],
            capture_output=True, text=True, timeout=180)
    finally:
        shutil.rmtree(profile, ignore_errors=True)


class Page(html.parser.HTMLParser):
    """The body's attributes, the [data-key] numbers with their text, and some texts."""

    def __init__(self):
        super().__init__()
        self.body = {}
        self.numbers = []  # [attrs, text]
        self.open_number = None
        self.number_depth = 0
        self.where = []
        self.code = []
        self.counts = {}
        self.links = []
        self.errors = []
        self.stack = []

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        self.stack.append((tag, a))
        if tag == "body":
            self.body = a
        if "data-key" in a:
            self.open_number = [a, ""]
            self.number_depth = len(self.stack)
            self.numbers.append(self.open_number)
        if tag == "a" and "href" in a:
            self.links.append(a["href"])

    def handle_endtag(self, tag):
        while self.stack:
            t, _ = self.stack.pop()
            if t == tag:
                break
        if self.open_number is not None and len(self.stack) < self.number_depth:
            self.open_number = None

    def handle_data(self, text):
        if self.open_number is not None:
            self.open_number[1] += text
        if not self.stack:
            return
        tag, a = self.stack[-1]
        if a.get("class") == "where":
            self.where.append(text)
        if tag == "code":
            self.code.append(text)
        if "data-count" in a:
            self.counts[a["data-count"]] = int(text)
        if "job-error" in a.get("class", ""):
            self.errors.append(text)


def open_page(path, fragment=""):
    url = "file://" + os.path.abspath(path) + fragment
    p = chromium(url, ["--dump-dom"])
    consoles = [l for l in p.stderr.splitlines() if ":CONSOLE" in l]
    check(not consoles, f"{path}: console messages: {consoles[:3]}")
    page = Page()
    page.feed(p.stdout)
    check(page.body.get("data-ready") == "1", f"{path}: the page did not finish drawing")
    check(page.body.get("data-errors") == "[]",
          f"{path}: script errors {page.body.get('data-errors')}")
    return page


def value_at(summary, key):
    v = summary
    for part in key.split("."):
        v = v[int(part)] if isinstance(v, list) else v[part]
    return v


def check_numbers(page, summary, where, required):
    seen = set()
    for attrs, text in page.numbers:
        key = attrs["data-key"]
        seen.add(key)
        try:
            expected = value_at(summary, key)
        except (KeyError, IndexError, TypeError):
            check(False, f"{where}: the page shows {key}, which summary.json does not have")
            continue
        if expected is None:
            check(text.strip() == "–", f"{where}: {key} is null but shown as {text!r}")
            continue
        # The page carries the file's number exactly ...
        check(float(attrs["data-value"]) == float(expected),
              f"{where}: {key} carried as {attrs['data-value']}, summary.json {expected}")
        # ... and shows it to four significant digits (rounding: half a unit of the 4th digit,
        # 5e-4 of the value at most; integers of 5+ digits are shown whole).
        shown = float(text.strip().replace("−", "-"))
        scaled = float(expected) * float(attrs.get("data-scale", "1"))
        check(math.isclose(shown, scaled, rel_tol=5e-4, abs_tol=1e-12),
              f"{where}: {key} shown as {text.strip()}, summary.json {scaled}")
    for key in required:
        check(key in seen, f"{where}: {key} is not on the page")
    print(f"{where}: {len(page.numbers)} numbers compared with summary.json's")


def check_drawn(page, where, plots, view):
    check(int(page.body.get("data-plots", "0")) == plots,
          f"{where}: {page.body.get('data-plots')} plots drawn, expected {plots}")
    # A plot with its curves, axes and grid paints thousands of pixels; an empty one none.
    check(int(page.body.get("data-plot-pixels", "0")) > 1000,
          f"{where}: a plot is blank ({page.body.get('data-plot-pixels')} pixels)")
    if view:
        # The stock fills a good part of the 700 x 520 view (over 5 %).
        check(int(page.body.get("data-view-pixels", "0")) > 0.05 * 700 * 520,
              f"{where}: the 3D view is blank ({page.body.get('data-view-pixels')} pixels)")


def check_screenshot(path, where):
    png = os.path.join(OUT, os.path.basename(os.path.dirname(path)) + ".png")
    chromium("file://" + os.path.abspath(path), ["--screenshot=" + png])
    check(os.path.exists(png), f"{where}: no screenshot")
    try:
        from PIL import Image
    except ImportError:
        check(False, "python3-pil is not installed")
        return
    im = Image.open(png).convert("RGB")
    colours = im.getcolors(maxcolors=1 << 20)
    # Text, plots and the shaded stock give thousands of colours; a blank page one.
    check(colours is not None and len(colours) > 500,
          f"{where}: the screenshot looks blank ({len(colours or [])} colours)")


def check_selection(path, summary, program, where):
    step = summary["peak_mrr"]["step"]
    line = summary["peak_mrr"]["line"]
    page = open_page(path, f"#step={step}")
    text = "".join(page.where)
    check(text.startswith(f"step {step} ") and f"{os.path.basename(program)}:{line} " in text,
          f"{where}: #step={step} selected {text!r}, expected step {step} at line {line}")
    with open(program) as f:
        source = f.read().splitlines()[line - 1].strip()
    check(source in [c.strip() for c in page.code],
          f"{where}: the selected step's G-code {page.code} is not line {line}: {source!r}")


def check_run(out, program, plots, view, required):
    path = os.path.join(out, "report.html")
    with open(os.path.join(out, "summary.json")) as f:
        summary = json.load(f)
    page = open_page(path)
    check_drawn(page, path, plots, view)
    check_numbers(page, summary, path, required)
    check_selection(path, summary, program, path)
    return path


shutil.rmtree(OUT, ignore_errors=True)
os.makedirs(OUT)

# A schedule with cutting physics: six plots, the 3D view.
fig9 = os.path.join(DATA, "gcode/paper/fig9_corner.ngc")
out = os.path.join(OUT, "fig9_chip")
run(["schedule", fig9, "--tool", "flat", "--diameter", "6mm", "--stock", "box:-30,-10,-10,10,30,0",
     "--material", "aluminium-7075-t6", "--spindle", "10000rpm", "--max-chip", "0.04mm",
     "--max-power", "0.3kW", "--out", out])
path = check_run(out, fig9, 6, True,
                 ["removed", "peak_mrr.value", "peak_mrr.line", "schedule.cycle_time_before_s",
                  "schedule.cycle_time_after_s", "physics.peaks.f_peak.value",
                  "agreement_exact.straight.mean_relative", "collisions.count",
                  "schedule.verified.checks.0.worst", "schedule.lines.0.feed_lowest"])
check_screenshot(path, path)

# An inch program on the dexel stock: in inches, the 3D view from the dexels.
helix = os.path.join(DATA, "gcode/dialects/inch_helix.ngc")
out = os.path.join(OUT, "inch_helix")
run(["simulate", helix, "--tool", "flat", "--diameter", "0.25in", "--stock",
     "box:-0.5,-0.5,-0.6,2,1,0", "--voxel", "0.02in", "--stock-model", "dexel", "--out", out])
check_run(out, helix, 2, True, ["removed", "peak_mrr.value"])
with open(os.path.join(out, "summary.json")) as f:
    check(json.load(f)["units"] == "in", "inch_helix: not an inch run")

# A program that changes tools: the tools' table.
three = os.path.join(DATA, "gcode/multitool/three_tools.ngc")
out = os.path.join(OUT, "three_tools")
run(["simulate", three, "--tools", os.path.join(DATA, "tools/three_tools.json"), "--stock",
     "box:0,0,-10,60,40,0", "--out", out])
check_run(out, three, 2, True,
          ["tools.0.removed", "tools.1.removed", "tools.2.removed", "tools.2.peak_mrr.line"])

# A run against its part (exit status 7: a gouge): the part's card and section with the line
# that cut the gouge and its G-code, the 3D view coloured by the deviation.
pocket = os.path.join(DATA, "gcode/part_check/pocket_gouge.ngc")
out = os.path.join(OUT, "part")
run(["simulate", pocket, "--tool", "flat", "--diameter", "6mm", "--stock", "box:0,0,-10,40,40,0",
     "--part", os.path.join(DATA, "gcode/part_check/pocket_part.obj"), "--out", out], status=7)
check_run(out, pocket, 2, True,
          ["part.gouges.count", "part.gouges.deepest", "part.gouges.regions.0.depth",
           "part.gouges.regions.0.volume", "part.gouges.regions.0.lines.0.floor_area",
           "part.leftovers.regions.0.thickness"])
page = open_page(os.path.join(out, "report.html"))
check("G1 X27 F600" in [c.strip() for c in page.code],
      f"part: the gouging line's G-code is not on the page: {page.code}")

# A batch with a failing job; --outputs tables: the jobs' reports without 3D view.
out = os.path.join(OUT, "batch")
manifest = os.path.join(SOURCE, "tests/data/batch/manifest.json")
subprocess.run([ENGAGE, "batch", manifest, "--out", out, "--quiet", "--outputs", "tables"],
               capture_output=True, text=True)
page = open_page(os.path.join(out, "report.html"))
with open(os.path.join(out, "batch.json")) as f:
    batch = json.load(f)
check(page.counts.get("all") == len(batch["records"]) == 5,
      f"batch: {page.counts.get('all')} rows, batch.json {len(batch['records'])}, expected 5")
check(page.counts.get("failed") == batch["failed"] == 1, f"batch: failed {page.counts}")
check(any("modal group" in e for e in page.errors), f"batch: the error is not shown: {page.errors}")
for r in batch["records"]:
    link = f"jobs/{r['name']}/report.html"
    if r["status"] == "ok":
        check(link in page.links and os.path.exists(os.path.join(out, link)),
              f"batch: no working link to {link}")
        # A tables job's report: plots, no 3D view.
        job = open_page(os.path.join(out, link))
        check(job.body.get("data-view-pixels") == "-1", f"{link}: a 3D view without stock files")
    else:
        check(link not in page.links, f"batch: a link to the failed job's {link}")

print(f"{len(failures)} failed" if failures else "report pages: all checks passed")
sys.exit(1 if failures else 0)

#!/usr/bin/env python3
"""The report's hover tooltips in a real browser (headless Chromium driven over the DevTools
protocol on a pipe, no network, no package beyond Python's own): the pointer moved onto a
residual point shows that point's values (its SVG <title>, which a page without script shows
too), and onto the peak of the predicted elongation, a line, shows the time, the value and its
band read back from the line's pixels, which must agree with prediction_time.csv.

    report_hover_test.py [REPORT]   (default fits/cheng2017/report.html)

Exit 77 (skipped) when Chromium is not installed."""
import csv
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
report = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "fits/cheng2017/report.html"))
browser = shutil.which("chromium") or shutil.which("chromium-browser")
if not browser:
    print("SKIP: chromium is not installed (scripts/install-deps.sh installs it): the hover is not tested")
    sys.exit(77)


def fail(message):
    print("FAIL: " + message)
    sys.exit(1)


class DevTools:
    """Chromium with --remote-debugging-pipe: JSON messages ending in NUL, it reads fd 3 and writes fd 4."""

    def __init__(self):
        self.profile = tempfile.mkdtemp()
        to_browser_r, self.to_browser = os.pipe()
        self.from_browser, from_browser_w = os.pipe()

        def child_fds():
            os.dup2(to_browser_r, 3)
            os.dup2(from_browser_w, 4)

        self.process = subprocess.Popen(
            [browser, "--headless", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--no-first-run",
             "--user-data-dir=" + self.profile, "--remote-debugging-pipe", "--window-size=1300,1000", "about:blank"],
            # 3 and 4 kept: the child closes what pass_fds does not name after child_fds has run
            pass_fds=(3, 4, to_browser_r, from_browser_w), preexec_fn=child_fds, stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL)
        os.close(to_browser_r)
        os.close(from_browser_w)
        self.buffer = b""
        self.next_id = 0
        self.session = None

    def send(self, method, params=None, session=True):
        self.next_id += 1
        message = {"id": self.next_id, "method": method, "params": params or {}}
        if session and self.session:
            message["sessionId"] = self.session
        os.write(self.to_browser, json.dumps(message).encode() + b"\0")
        while True:
            while b"\0" not in self.buffer:
                chunk = os.read(self.from_browser, 1 << 16)
                if not chunk:
                    fail("chromium closed the DevTools pipe")
                self.buffer += chunk
            raw, self.buffer = self.buffer.split(b"\0", 1)
            reply = json.loads(raw)
            if reply.get("id") == self.next_id:
                if "error" in reply:
                    fail(f"{method}: {reply['error']}")
                return reply.get("result", {})

    def evaluate(self, expression):
        result = self.send("Runtime.evaluate", {"expression": expression, "returnByValue": True, "awaitPromise": True})
        if "exceptionDetails" in result:
            fail(f"script error: {result['exceptionDetails']}")
        return result["result"].get("value")

    def close(self):
        self.process.kill()
        self.process.wait()
        shutil.rmtree(self.profile, ignore_errors=True)


chrome = DevTools()
try:
    target = chrome.send("Target.createTarget", {"url": "about:blank"}, session=False)["targetId"]
    chrome.session = chrome.send("Target.attachToTarget", {"targetId": target, "flatten": True}, session=False)["sessionId"]
    chrome.send("Page.enable")
    chrome.send("Page.navigate", {"url": "file://" + report})
    chrome.evaluate("new Promise(r => { if (document.readyState === 'complete') r(); else addEventListener('load', () => r()); })")

    def hover(plot, where):
        """Scrolls plot into view, moves the pointer onto the SVG point `where` returns (in the
        svg's own coordinates), and returns the tooltip's text ('' when none shows)."""
        position = chrome.evaluate(f"""(() => {{
          const s = document.querySelector('svg[data-plot="{plot}"]');
          if (!s) return null;
          s.scrollIntoView({{block: 'center'}});
          const p = ({where})(s);
          if (!p) return null;
          const q = new DOMPoint(p.x, p.y).matrixTransform(s.getScreenCTM());
          return {{x: q.x, y: q.y, expected: p.expected || ''}};
        }})()""")
        if position is None:
            fail(f"plot {plot}: nothing to hover")
        for kind in ("mouseMoved",):
            chrome.send("Input.dispatchMouseEvent", {"type": kind, "x": position["x"], "y": position["y"]})
        shown = chrome.evaluate("(() => { const t = document.querySelector('.lmcal-tip'); "
                                "return t && !t.hidden && t.offsetWidth > 0 ? t.textContent : ''; })()")
        return shown, position["expected"]

    # A point (the one farthest from the others, so that it is the nearest to the pointer; of
    # those whose values `holding` is in, when given): its tooltip is its own <title>, with the
    # axes' names and its values.
    def hover_point(plot, holding=""):
        return hover(plot, """s => {
          const points = [...s.querySelectorAll('g.data circle')].filter(c => c.querySelector('title'))
            .map(c => ({x: +c.getAttribute('cx'), y: +c.getAttribute('cy'), expected: c.querySelector('title').textContent}));
          let best = null, farthest = -1;
          for (const p of points.filter(p => p.expected.includes(%s))) {
            const nearest = Math.min(...points.filter(q => q !== p).map(q => Math.hypot(p.x - q.x, p.y - q.y)));
            if (nearest > farthest) { farthest = nearest; best = p; }
          }
          return best;
        }""" % json.dumps(holding))

    shown, expected = hover_point("friction-residual-direction")
    if not expected:
        fail("the residual points carry no <title>")
    if shown != expected:
        fail(f"hovering a residual point shows {shown!r}, expected its values {expected!r}")
    if not re.search(r"direction \(\+1 forward, -1 backward\) [-+0-9.e]+, mean residual \(N\) [-+0-9.e]+", shown):
        fail(f"the point's tooltip lacks its values: {shown!r}")

    # Run names that are markup (report_markup_test.sh's): their points' tooltips show them as text.
    markup = chrome.evaluate("""(() => { for (const s of document.querySelectorAll('svg.plot'))
      for (const t of s.querySelectorAll('g.data circle title')) if (t.textContent.includes('<')) return s.dataset.plot;
      return null; })()""")
    if markup:
        shown, expected = hover_point(markup, "<")
        if shown != expected or "<" not in shown:
            fail(f"hovering a point named with markup shows {shown!r}, expected the text {expected!r}")
        if chrome.evaluate("document.querySelectorAll('img, .lmcal-tip *').length"):
            fail("a name in a tooltip became markup")

    if not chrome.evaluate("!!document.querySelector('svg[data-plot=\"prediction-elongation\"]')"):
        if os.path.basename(os.path.dirname(report)) == "cheng2017":
            fail("the bundled report has no prediction-elongation plot to hover")
        print(f"ok: hovering a point shows its values{'; names that are markup as text' if markup else ''} "
              "(no prediction plot: the line not tested)")
        sys.exit(0)

    # A line: the peak of the predicted elongation, its time and value and band from the pixels.
    shown, _ = hover("prediction-elongation", """s => {
      const d = s.querySelector('g.data path.line').getAttribute('d');
      let best = null;
      for (const m of d.matchAll(/[ML](-?[0-9.]+) (-?[0-9.]+)/g))
        if (!best || +m[2] < best.y) best = {x: +m[1], y: +m[2]};
      return best;
    }""")
    match = re.fullmatch(r"model \(95 % band\): time \(h\) ([0-9.]+), elongation \(µm\) ([0-9.]+) \[([0-9.]+), ([0-9.]+)\]", shown)
    if not match:
        fail(f"hovering the elongation's peak shows {shown!r}, expected the time, the value and its band")
    time_h, value, low, high = map(float, match.groups())
    table = os.path.join(os.path.dirname(report), "prediction_time.csv")
    if os.path.exists(table):
        rows = [row for row in csv.DictReader(open(table)) if row["quantity"] == "elongation_um"]
        peak = max(float(row["value"]) for row in rows)
        at = min(rows, key=lambda row: abs(float(row["time_s"]) - 3600 * time_h))  # the record at the tooltip's time
        if abs(float(at["time_s"]) - 3600 * time_h) > 120:
            fail(f"the tooltip's time {time_h} h is no record's of prediction_time.csv")
        for got, column in ((value, "value"), (low, "low"), (high, "high")):
            if abs(got - float(at[column])) > 0.005 * peak:
                fail(f"the tooltip at {time_h} h says {column} {got}; prediction_time.csv {at[column]}")
        if not low <= value <= high:
            fail(f"the tooltip's band [{low}, {high}] does not hold its value {value}")
    # Away from every point: no tooltip.
    shown, _ = hover("prediction-elongation", "s => ({x: 2, y: 2})")
    if shown:
        fail(f"a tooltip shows away from the data: {shown!r}")
finally:
    chrome.close()
print("ok: hovering a point shows its values, hovering a line its value and band at the nearest vertex")

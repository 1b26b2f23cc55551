#!/usr/bin/env python3
"""Every plot of a report, read from its SVG (no browser): a title; on each axis two labelled
ticks or more (or the names of its runs); no text outside the viewBox as the layout measures
text (6.2 px a glyph at 11 px, in proportion at other sizes, bold 1.1 times wider; upright text
runs up from its anchor); no two x tick labels running into each other; every point drawn with
a <title> giving its values (the tooltip without script), every line with one.

    report_svg_test.py [REPORT...]   (default: the bundled report, fits/cheng2017/report.html)"""
import os
import re
import sys
import xml.etree.ElementTree as ET

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SVG = "{http://www.w3.org/2000/svg}"


def glyphs(text):
    return len(text)  # code points: ElementTree decodes the UTF-8


def outside(svg, width, height):
    """The texts whose estimated extent leaves the viewBox."""
    out = []
    for t in svg.iter(SVG + "text"):
        x, y, anchor = float(t.get("x")), float(t.get("y")), t.get("text-anchor", "start")
        size = float(t.get("font-size", 11))
        length = glyphs(t.text or "") * 6.2 * size / 11 * (1.1 if t.get("font-weight") == "bold" else 1)
        before = {"start": 0, "middle": length / 2, "end": length}[anchor]
        if "rotate(-90" in (t.get("transform") or ""):
            box = (x - 0.8 * size, x + 0.25 * size, y - (length - before), y + before)
        else:
            box = (x - before, x - before + length, y - 0.8 * size, y + 0.25 * size)
        if box[0] < -0.5 or box[1] > width + 0.5 or box[2] < -0.5 or box[3] > height + 0.5:
            out.append(t.text)
    return out


def problems(svg):
    width, height = map(float, svg.get("viewBox").split()[2:])
    found = []
    if svg.find(SVG + "g[@class='data']") is None:  # "no data": nothing to label
        return found
    if not svg.get("data-x") or not svg.get("data-y"):
        found.append("no axis scales for the hover script (data-x, data-y)")
    if not any(t.get("class") == "title" and (t.text or "").strip() for t in svg.iter(SVG + "text")):
        found.append("no title")
    labels = svg.find(SVG + "g[@class='tick-labels']")
    x_ticks = [t for t in labels.iter(SVG + "text") if t.get("class") == "x-tick"] if labels is not None else []
    y_ticks = [t for t in labels.iter(SVG + "text") if t.get("class") != "x-tick"] if labels is not None else []
    if len(x_ticks) < 2 or len(y_ticks) < 2:
        found.append(f"{len(x_ticks)} x and {len(y_ticks)} y tick labels")
    if len({t.text for t in y_ticks}) < len(y_ticks):
        found.append("y tick labels repeat")
    spans = sorted((float(t.get("x")) - 3.1 * glyphs(t.text), float(t.get("x")) + 3.1 * glyphs(t.text))
                   for t in x_ticks if t.get("text-anchor") == "middle")
    if any(b[0] < a[1] for a, b in zip(spans, spans[1:])):
        found.append("x tick labels run into each other")
    if (text := outside(svg, width, height)):
        found.append(f"outside the viewBox: {text}")
    data = svg.find(SVG + "g[@class='data']")
    for series in data.iter(SVG + "g") if data is not None else []:
        if any(c.find(SVG + "title") is None for c in series.iter(SVG + "circle")):
            found.append(f"a point of '{series.get('data-label')}' without its values")
        if any(p.get("class") == "line" and p.find(SVG + "title") is None for p in series.iter(SVG + "path")):
            found.append(f"a line of '{series.get('data-label')}' without a tooltip")
    return found


def main(reports):
    failures, plots = [], 0
    for report in reports:
        html = open(report, encoding="utf-8").read()
        for match in re.finditer(r"<svg xmlns=.*?</svg>", html, re.S):
            svg = ET.fromstring(match.group(0))
            plots += 1
            failures += [f"{os.path.relpath(report, ROOT)} {svg.get('data-plot')}: {p}" for p in problems(svg)]
    for f in failures:
        print("FAIL: " + f)
    if not plots:
        print("FAIL: no plots found")
        return 1
    if not failures:
        print(f"ok: {plots} plots in {len(reports)} reports: titled, two tick labels an axis or more, inside their "
              "viewBox, every point and line with its tooltip")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:] or [os.path.join(ROOT, "fits/cheng2017/report.html")]))

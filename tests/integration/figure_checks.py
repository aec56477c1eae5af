"""Checks of a figure drawn by radar-emu's plotting layer (plot/charts.hpp, plot/render.py), read
back independently of the writer: the PNG's size from its IHDR chunk, and the SVG beside it
parsed with xml.etree: every data panel's axis labels carry a unit in brackets, and every colour
bar's label does too (docs/plotting.md). Shared by the CLI checks that already make the figures
(check_figures.py, check_image_cli.py, check_sar_cli.py, check_tradeoff_cli.py)."""
import os
import re
import struct
import xml.etree.ElementTree as ET

SVG = "{http://www.w3.org/2000/svg}"
UNIT = re.compile(r"\[[^\]]+\]")


def png_size(path):
    with open(path, "rb") as f:
        head = f.read(24)
    if head[:8] != b"\x89PNG\r\n\x1a\n" or head[12:16] != b"IHDR":
        return None
    return struct.unpack(">II", head[16:24])


def _text(e):
    return "".join("".join(t.itertext()) for t in e.iter(SVG + "text")).strip()


def _axis_label(axis):
    """The label of a matplotlib.axis group: its own text group, not a tick's."""
    for child in axis:
        cid = child.get("id", "")
        if cid.startswith("text_"):
            return _text(child)
    return ""


def panels(svg_path):
    """[(x label, y label, is colour bar, all texts)] of every axes in the SVG."""
    root = ET.parse(svg_path).getroot()
    out = []
    for g in root.iter(SVG + "g"):
        if not g.get("id", "").startswith("axes_"):
            continue
        axes = [c for c in g if c.get("id", "").startswith("matplotlib.axis_")]
        if len(axes) < 2:
            continue
        xl, yl = _axis_label(axes[0]), _axis_label(axes[1])
        x_ticks = _text(axes[0])
        colour_bar = xl == "" and x_ticks == "" and yl != ""
        out.append((xl, yl, colour_bar, _text(g)))
    return out


def check_figure(png, size=None, colour_bars=None, texts=()):
    """Failures (strings) of the figure `png` and its SVG: `size` (w, h) if given; every data
    panel's x and y labels with a [unit] (a polar panel: its angle label, and its radius label
    among its texts); `colour_bars`: how many colour bars, each label with a [unit]; `texts`:
    strings that must appear among the SVG's texts."""
    bad = []
    if not os.path.exists(png):
        return [f"{png}: missing"]
    got = png_size(png)
    if got is None:
        bad.append(f"{png}: not a PNG")
    elif size is not None and tuple(got) != tuple(size):
        bad.append(f"{png}: {got[0]} x {got[1]} pixels, want {size[0]} x {size[1]}")
    svg = os.path.splitext(png)[0] + ".svg"
    if not os.path.exists(svg):
        return bad + [f"{svg}: missing"]
    ps = panels(svg)
    data = [p for p in ps if not p[2]]
    bars = [p for p in ps if p[2]]
    if not data:
        bad.append(f"{svg}: no data panel")
    for xl, yl, _, all_text in data:
        if not UNIT.search(xl):
            bad.append(f"{svg}: x label '{xl}' has no [unit]")
        if yl and not UNIT.search(yl):
            bad.append(f"{svg}: y label '{yl}' has no [unit]")
        if not yl and len(UNIT.findall(all_text)) < 2:  # polar: the radius label is a text
            bad.append(f"{svg}: a panel with x label '{xl}' has no y label with a [unit]")
    if colour_bars is not None and len(bars) != colour_bars:
        bad.append(f"{svg}: {len(bars)} colour bar(s), want {colour_bars}")
    for _, yl, _, _ in bars:
        if not UNIT.search(yl):
            bad.append(f"{svg}: colour bar label '{yl}' has no [unit]")
    every = " ".join(p[3] for p in ps)
    root_text = _text(ET.parse(svg).getroot())
    for t in texts:
        if t not in every and t not in root_text:
            bad.append(f"{svg}: no text '{t}'")
    return bad

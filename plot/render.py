# radar-emu's figure renderer (docs/plotting.md): draws the figures the C++ tools describe
# (plot/charts.hpp, serialised to JSON by plot/charts.cpp) with matplotlib, as an anti-aliased
# PNG and an SVG beside it whose text stays text. The binary carries this file (embedded at build
# time) and runs it with the Python interpreter CMake found:
#   python3 render.py SPEC.json
# Exit status: 0 drawn; 3 matplotlib (or NumPy) missing; 2 any other failure, with one line on
# stderr naming the figure.
import json
import math
import os
import sys
import textwrap

try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker
    import numpy as np
    from matplotlib import colors as mcolors
except ImportError as e:  # the caller turns this into its own one-line message
    print(f"missing-matplotlib: {e}", file=sys.stderr)
    sys.exit(3)

DPI = 100  # figure pixels = inches x DPI, so a spec's width and height are the PNG's pixels

matplotlib.rcParams.update({
    "font.family": "DejaVu Sans",
    "font.size": 11,
    "axes.titlesize": 12,
    "figure.titlesize": 13,
    "svg.fonttype": "none",  # text stays text in the SVG (readable, searchable, testable)
    "svg.hashsalt": "radar-emu",  # stable ids: an unchanged figure gives an unchanged file
    "axes.grid": True,
    "grid.color": "0.88",
    "grid.linewidth": 0.8,
    "axes.axisbelow": True,
    "legend.fontsize": 10,
    "legend.frameon": False,
    "image.cmap": "viridis",
    "figure.dpi": DPI,
    "savefig.dpi": DPI,
})

MISSING_GREY = "0.67"  # non-finite cells


class PlainLogFormatter(matplotlib.ticker.LogFormatterSciNotation):
    """Log-axis labels as matplotlib chooses them, written plainly ("200", "0.05") between
    0.001 and 10^4 and as powers of ten outside (docs/plotting.md)."""

    def __call__(self, x, pos=None):
        s = super().__call__(x, pos)
        if s and 1e-3 <= abs(x) <= 1e4:
            return f"{x:g}"
        return s


def unit_of(label):
    """The unit in the last [...] of an axis label ("range [m]" -> "m"); "" when none."""
    i = label.rfind("[")
    j = label.find("]", i + 1) if i >= 0 else -1
    return label[i + 1:j] if i >= 0 and j > i else ""


def arr(v):
    """JSON list (null for a non-finite value) -> float array with NaN."""
    return np.array([math.nan if x is None else x for x in v], dtype=float)


def wrap(text, width_px, size_px=8.5):
    if not text:
        return ""
    return "\n".join(textwrap.wrap(text, max(20, int(width_px / size_px))))


def nice_125(v):
    """The largest 1, 2 or 5 times a power of ten at most v."""
    mag = 10.0 ** math.floor(math.log10(v))
    for m in (5.0, 2.0, 1.0):
        if m * mag <= v * (1 + 1e-12):
            return m * mag
    return mag


def cell_edges(c):
    """Cell edges of pixel centres: midpoints, the ends half a spacing out."""
    if len(c) == 1:
        return np.array([c[0] - 0.5, c[0] + 0.5])
    mid = 0.5 * (c[1:] + c[:-1])
    return np.concatenate([[c[0] - (mid[0] - c[0])], mid, [c[-1] + (c[-1] - mid[-1])]])


def place_legend(ax, fig_w_px, below=None):
    handles, labels = ax.get_legend_handles_labels()
    if not handles:
        return
    longest = max(len(s) for s in labels)
    if below is None:
        below = longest * 7 > 0.3 * fig_w_px or len(labels) > 14
    if below:
        ncol = max(1, min(len(labels), int(fig_w_px / (longest * 7 + 50))))
        ax.legend(handles, labels, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=ncol)
    else:
        ax.legend(handles, labels, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0)


def draw_line(fig, ax, p, fig_w_px, panel_w_px):
    polar = p.get("polar", False)
    stacked = [s for s in p["series"] if s.get("stacked")]
    cycle = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for k, s in enumerate(p["series"]):
        s["_colour"] = s.get("colour") or cycle[k % len(cycle)]
    if stacked:
        x = arr(stacked[0]["x"])
        ys = [np.nan_to_num(arr(s["y"])) for s in stacked]
        ax.stackplot(x, ys, labels=[s.get("label", "") for s in stacked],
                     colors=[s["_colour"] for s in stacked], alpha=0.85, linewidth=0)
    mappable = None
    for s in p["series"]:
        if s.get("stacked"):
            continue
        x, y = arr(s["x"]), arr(s["y"])
        if polar:
            x = np.radians(x)
        col = s["_colour"]
        label = s.get("label") or None
        if s.get("colour_values"):
            mappable = ax.scatter(x, y, c=arr(s["colour_values"]), s=s.get("marker_size", 12),
                                  cmap=p.get("colour_map", "viridis"), vmin=p.get("colour_min"),
                                  vmax=p.get("colour_max"), label=label, linewidths=0)
            continue
        ls = "--" if s.get("dashed") else "-"
        if s.get("no_line"):
            ls = "none"
        marker = "o" if s.get("markers") or len(x) == 1 else None
        ax.plot(x, y, linestyle=ls, marker=marker, markersize=6 if ls == "none" else 4,
                markeredgecolor="white" if ls == "none" else col, markeredgewidth=0.6,
                color=col, label=label, linewidth=1.6)
        ylo, yhi = s.get("y_lo"), s.get("y_hi")
        xlo, xhi = s.get("x_lo"), s.get("x_hi")
        if ylo or xlo:
            yerr = [y - arr(ylo), arr(yhi) - y] if ylo else None
            xerr = [x - arr(xlo), arr(xhi) - x] if xlo else None
            ax.errorbar(x, y, yerr=yerr, xerr=xerr, fmt="none", ecolor=col, elinewidth=1.0,
                        capsize=3, alpha=0.8)
        for xi, yi, t in zip(x, y, s.get("point_labels") or []):
            if t and np.isfinite(xi) and np.isfinite(yi):
                ax.annotate(t, (xi, yi), xytext=(4, 4), textcoords="offset points", fontsize=8,
                            color=col)
    for r in p.get("ref_lines", []):
        kw = dict(color=r.get("colour", "0.2"), linestyle=r.get("style", "--"), linewidth=1.4,
                  label=r.get("label") or None)
        (ax.axvline if r.get("vertical") else ax.axhline)(r["value"], **kw)
    if polar:
        ax.set_theta_zero_location(p.get("theta_zero", "N"))
        ax.set_theta_direction(-1 if p.get("clockwise", True) else 1)
        if p.get("y_min") is not None or p.get("y_max") is not None:
            ax.set_rlim(p.get("y_min"), p.get("y_max"))
        ax.set_rlabel_position(p.get("r_label_deg", 22.5))
        ax.set_xlabel(p.get("x_label", ""))
        ax.text(0.0, 1.02, p.get("y_label", ""), transform=ax.transAxes, ha="left", va="bottom")
    else:
        if p.get("log_x"):
            ax.set_xscale("log")
            ax.xaxis.set_major_formatter(PlainLogFormatter())
            ax.xaxis.set_minor_formatter(PlainLogFormatter(labelOnlyBase=False,
                                                           minor_thresholds=(2, 0.5)))
        if p.get("log_y"):
            ax.set_yscale("log")
            ax.yaxis.set_major_formatter(PlainLogFormatter())
            ax.yaxis.set_minor_formatter(PlainLogFormatter(labelOnlyBase=False,
                                                           minor_thresholds=(2, 0.5)))
        if p.get("log_x") or p.get("log_y"):
            ax.grid(True, which="minor", color="0.95", linewidth=0.6)
        ax.set_xlim(p.get("x_min"), p.get("x_max"))
        ax.set_ylim(p.get("y_min"), p.get("y_max"))
        ax.set_xlabel(p.get("x_label", ""))
        ax.set_ylabel(p.get("y_label", ""))
        if p.get("equal_aspect"):
            ax.set_aspect("equal", adjustable="datalim")
    if mappable is not None:
        cb = fig.colorbar(mappable, ax=ax, pad=0.02)
        cb.set_label(p.get("colour_label", ""))
    if p.get("title"):
        ax.set_title(wrap(p["title"], panel_w_px))
    if p.get("legend", True):
        place_legend(ax, panel_w_px, p.get("legend_below"))


def draw_heatmap(fig, ax, p, panel_w_px, panel_h_px, arrays):
    x, y = arr(p["x"]), arr(p["y"])
    ex, ey = cell_edges(x), cell_edges(y)
    eq = p.get("equal_aspect")
    if eq is None:
        xu = unit_of(p.get("x_label", ""))
        eq = bool(xu) and xu == unit_of(p.get("y_label", ""))
    if p.get("rgb_file"):
        rgb = np.fromfile(os.path.join(arrays, p["rgb_file"]), dtype=np.uint8)
        rgb = rgb.reshape(len(y), len(x), 3)
        ax.imshow(rgb, extent=[ex[0], ex[-1], ey[0], ey[-1]], origin="lower",
                  interpolation="nearest", aspect="auto")
        ax.grid(False)
    else:
        v = np.fromfile(os.path.join(arrays, p["values_file"]), dtype="<f8")
        v = np.ma.masked_invalid(v.reshape(len(y), len(x)))
        cmap = matplotlib.colormaps["gray" if p.get("grey") else p.get("colour_map", "viridis")]
        cmap = cmap.with_extremes(bad=MISSING_GREY)
        hi = p["value_max"]
        lo = hi - p["value_range"]
        mesh = ax.pcolormesh(ex, ey, v, cmap=cmap, vmin=lo, vmax=hi, shading="flat",
                             rasterized=True)
        ax.grid(False)
        shrink = 1.0
        if eq:  # the colour bar as tall as the letterboxed image (room for labels estimated)
            box_w, box_h = max(100.0, panel_w_px - 230.0), max(100.0, panel_h_px - 110.0)
            shrink = min(1.0, max(0.3, box_w * (ey[-1] - ey[0]) / (ex[-1] - ex[0]) / box_h))
        cb = fig.colorbar(mesh, ax=ax, pad=0.02, shrink=shrink)
        cb.set_label(p.get("value_label", ""))
    ax.set_xlim(ex[0], ex[-1])
    ax.set_ylim(ey[0], ey[-1])
    ax.set_xlabel(p.get("x_label", ""))
    ax.set_ylabel(p.get("y_label", ""))
    ax.set_aspect("equal" if eq else "auto")
    sb = p.get("scale_bar")
    if sb is not None:
        from mpl_toolkits.axes_grid1.anchored_artists import AnchoredSizeBar
        span = ex[-1] - ex[0]
        length = sb if sb > 0 else nice_125(span / 5.0)
        bar = AnchoredSizeBar(ax.transData, length, f"{length:g} {unit_of(p.get('x_label', ''))}",
                              "lower left", pad=0.4, borderpad=0.6, sep=4, color="black",
                              frameon=True, size_vertical=span / 150.0)
        bar.patch.set_alpha(0.85)
        ax.add_artist(bar)
    if p.get("title"):
        ax.set_title(wrap(p["title"], panel_w_px))


def axes_record(fig, ax, p, height_px):
    """Where a panel's data area landed (PNG pixels, rows from the top) and its data ranges."""
    bb = ax.get_window_extent()
    rec = {"type": p["type"], "x0": bb.x0, "x1": bb.x1, "y0": height_px - bb.y1,
           "y1": height_px - bb.y0, "xlim": list(ax.get_xlim()), "ylim": list(ax.get_ylim()),
           "log_x": ax.get_xscale() == "log", "log_y": ax.get_yscale() == "log"}
    if p["type"] == "heatmap" and not p.get("rgb_file"):
        rec["value_lo"] = p["value_max"] - p["value_range"]
        rec["value_hi"] = p["value_max"]
        rec["colour_map"] = "gray" if p.get("grey") else p.get("colour_map", "viridis")
    return rec


def draw_figure(f, arrays):
    w, h = f["width"], f["height"]
    panels = f["panels"]
    cols = max(1, min(f.get("columns", 1), len(panels)))
    rows = (len(panels) + cols - 1) // cols
    # (A quarter pixel over: 8.2 inches x 100 dpi is 819.99..., which Agg truncates to 819.)
    fig = plt.figure(figsize=((w + 0.25) / DPI, (h + 0.25) / DPI), layout="constrained")
    if f.get("title"):
        fig.suptitle(wrap(f["title"], w))
    ratios = f.get("height_ratios")
    gs = fig.add_gridspec(rows, cols, height_ratios=ratios if ratios and len(ratios) == rows
                          else None)
    axes = []
    for i, p in enumerate(panels):
        spec = gs[i // cols, i % cols]
        ax = fig.add_subplot(spec, projection="polar" if p.get("polar") else None)
        panel_w = w / cols
        if p["type"] == "line":
            draw_line(fig, ax, p, w, panel_w)
        else:
            draw_heatmap(fig, ax, p, panel_w, h / rows, arrays)
        axes.append(ax)
    png = f["png"]
    fig.savefig(png, dpi=DPI, metadata={"Software": None})
    if f.get("svg"):
        fig.savefig(f["svg"], metadata={"Date": None, "Creator": None})
    if os.environ.get("RADAR_EMU_PLOT_AXES"):  # tests: where the data areas are
        fig.canvas.draw()
        recs = [axes_record(fig, ax, p, h) for ax, p in zip(axes, panels)]
        with open(os.path.splitext(png)[0] + ".axes.json", "w") as out:
            json.dump({"width": w, "height": h, "panels": recs}, out)
    plt.close(fig)


def main():
    with open(sys.argv[1]) as fh:
        spec = json.load(fh)
    arrays = os.path.dirname(os.path.abspath(sys.argv[1]))
    for f in spec["figures"]:
        try:
            draw_figure(f, arrays)
        except Exception as e:  # one line naming the figure
            msg = str(e).splitlines()[0] if str(e) else type(e).__name__
            print(f"{f['png']}: {type(e).__name__}: {msg}", file=sys.stderr)
            sys.exit(2)


if __name__ == "__main__":
    main()

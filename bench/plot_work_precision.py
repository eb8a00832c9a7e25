#!/usr/bin/env python3
"""Work-precision curves from bench/work_precision's CSV: error / scale (log) against cost (wall s per
variant-second, log), one panel per case, one line per simulator and method; MuJoCo's default
(Euler, 1 ms) starred; the settings that were unstable named under each panel.

Usage: plot_work_precision.py CSV [PNG]   (PNG defaults to docs/img/work_precision.png)
Needs matplotlib (Debian: python3-matplotlib, i.e. /usr/bin/python3).
"""
import csv
import sys
from collections import OrderedDict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

TITLES = {
    "rig6": "reference rig, N = 6\n(tip deflection RMS error / its RMS)",
    "rig24": "reference rig, N = 24\n(tip deflection RMS error / its RMS)",
    "arm": "rigid 6-DOF arm\n(largest joint-angle error at the end, rad)",
}
STYLE = {  # (colour, marker); flexfarm solid, MuJoCo dashed
    ("flexfarm", "midpoint"): ("tab:blue", "o"),
    ("flexfarm", "SDIRK2"): ("tab:green", "s"),
    ("flexfarm", "RK4"): ("tab:purple", "^"),
    ("flexfarm", "CVODE"): ("tab:gray", "D"),
    ("MuJoCo", "Euler"): ("tab:red", "o"),
    ("MuJoCo", "implicit"): ("tab:orange", "s"),
    ("MuJoCo", "RK4"): ("tab:brown", "^"),
}


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    out = sys.argv[2] if len(sys.argv) > 2 else "docs/img/work_precision.png"
    cases = OrderedDict()
    with open(sys.argv[1], newline="") as f:
        for r in csv.DictReader(f):
            cases.setdefault(r["case"], []).append(r)
    fig, axes = plt.subplots(1, len(cases), figsize=(5.2 * len(cases), 5.4), squeeze=False)
    for ax, (case, rows) in zip(axes[0], cases.items()):
        lines = OrderedDict()
        unstable = OrderedDict()
        for r in rows:
            key = (r["simulator"], r["method"])
            if r["stable"] != "1":
                unstable.setdefault(key, []).append(r["setting"].replace("h=", "").replace("us", "µs"))
                continue
            lines.setdefault(key, []).append((float(r["cost_s_per_variant_s"]), float(r["rel_error"]), r))
        for key, pts in lines.items():
            colour, marker = STYLE.get(key, ("black", "x"))
            ax.plot([p[0] for p in pts], [p[1] for p in pts], marker=marker, color=colour, markersize=4,
                    linestyle="-" if key[0] == "flexfarm" else "--", label=f"{key[0]} {key[1]}")
            for cost, err, r in pts:
                if key == ("MuJoCo", "Euler") and r["h_s"] and abs(float(r["h_s"]) - 1e-3) < 1e-12:
                    ax.plot([cost], [err], marker="*", color="black", markersize=14, linestyle="none",
                            label="MuJoCo default (Euler, 1 ms)", zorder=5)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.grid(True, which="major", alpha=0.4)
        ax.set_title(TITLES.get(case, case), fontsize=10)
        ax.set_xlabel("cost: wall s per variant-second (M variants, 2 threads)")
        ax.set_ylabel("error / scale")
        ax.legend(fontsize=7, loc="upper right")
        if unstable:
            text = "unstable: " + "; ".join(f"{k[0]} {k[1]} {', '.join(v)}" for k, v in unstable.items())
            ax.text(0.0, -0.2, text, transform=ax.transAxes, fontsize=6.5, va="top", wrap=True)
    fig.tight_layout()
    fig.savefig(out, dpi=110, bbox_inches="tight")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()

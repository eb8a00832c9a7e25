#!/usr/bin/env python3
"""Work-precision curves from bench/work_precision's CSV: error / scale (log) against cost (wall s per
variant-second, log), one panel per case, one line per simulator and method; MuJoCo's default
(Euler, 1 ms) starred; the settings that were unstable named under each panel.

Usage: plot_work_precision.py CSV [PNG]   (PNG defaults to docs/img/work_precision.png)
       plot_work_precision.py --table CSV  (Markdown tables for docs/performance.md: a row per step,
                                            a column per method, "error / scale · cost")
Needs matplotlib (Debian: python3-matplotlib, i.e. /usr/bin/python3) for the PNG.
"""
import csv
import sys
from collections import OrderedDict


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


def read(path):
    cases = OrderedDict()
    with open(path, newline="") as f:
        for r in csv.DictReader(f):
            cases.setdefault(r["case"], []).append(r)
    return cases


def table(cases):
    for case, rows in cases.items():
        methods = list(OrderedDict.fromkeys((r["simulator"], r["method"]) for r in rows if r["h_s"]))
        steps = sorted({float(r["h_s"]) for r in rows if r["h_s"]}, reverse=True)
        cell = {(r["simulator"], r["method"], float(r["h_s"])): r for r in rows if r["h_s"]}
        print(f"\n{case}: error / scale · cost (wall s per variant-second)\n")
        print("| h | " + " | ".join(f"{m[0]} {m[1]}" for m in methods) + " |")
        print("|---" * (len(methods) + 1) + "|")
        for h in steps:
            out = []
            for m in methods:
                r = cell.get((m[0], m[1], h))
                if r is None:
                    out.append("–")
                elif r["stable"] != "1":
                    out.append("unstable")
                else:
                    out.append(f"{float(r['rel_error']):.1e} · {float(r['cost_s_per_variant_s']):.2g}")
            label = f"{h * 1e3:g} ms" if h >= 1e-3 else f"{h * 1e6:g} µs"
            print(f"| {label} | " + " | ".join(out) + " |")
        cv = [r for r in rows if not r["h_s"]]
        if cv:
            print("\n| CVODE | " + " | ".join(r["setting"] for r in cv) + " |")
            print("|---" * (len(cv) + 1) + "|")
            print("| error / scale · cost | " + " | ".join(
                "unstable" if r["stable"] != "1" else
                f"{float(r['rel_error']):.1e} · {float(r['cost_s_per_variant_s']):.2g}" for r in cv) + " |")


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    if sys.argv[1] == "--table":
        return table(read(sys.argv[2]))
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = sys.argv[2] if len(sys.argv) > 2 else "docs/img/work_precision.png"
    cases = read(sys.argv[1])
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
        if unstable:
            text = "unstable: " + "\n".join(f"{k[0]} {k[1]} at h = {', '.join(v)}" for k, v in unstable.items())
            ax.text(0.02, 0.1, text, transform=ax.transAxes, fontsize=7, va="bottom")
    # One legend for all panels, below them.
    labels = OrderedDict()
    for ax in axes[0]:
        for handle, label in zip(*ax.get_legend_handles_labels()):
            labels.setdefault(label, handle)
    fig.tight_layout(rect=(0, 0.1, 1, 1))
    fig.legend(labels.values(), labels.keys(), loc="lower center", ncol=4, fontsize=8, frameon=False)
    fig.savefig(out, dpi=110, bbox_inches="tight")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()

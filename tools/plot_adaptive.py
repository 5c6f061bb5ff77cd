"""Error against time per scene for adaptive coarsening (tools/bench_adaptive.sh).

    python3 tools/plot_adaptive.py adaptive.csv out.png
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


# Uniform models: DDFEM level 2 / level 1, naive level 2 / level 1.
MARKERS = {"level2": "s", "level1": "^", "naive2": "x", "naive1": "+"}


def main() -> None:
    rows = list(csv.DictReader(open(sys.argv[1])))
    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    fig, ax = plt.subplots(figsize=(7.5, 5))
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for i, scene in enumerate(scenes):
        colour = colours[i % len(colours)]
        mine = [r for r in rows if r["scene"] == scene]
        fine = float(mine[0]["fine_seconds"])
        # In order of decreasing target; a run that chose the fine model
        # everywhere (error at round-off) has no place on a log axis.
        ad = [(float(r["seconds"]) / fine, float(r["error"]))
              for r in sorted((r for r in mine if r["model"] == "adaptive"), key=lambda r: -float(r["target"]))
              if float(r["error"]) > 1e-10]
        if ad:
            ax.plot([a for a, _ in ad], [e for _, e in ad], "o-", color=colour, label=scene)
        for model, marker in MARKERS.items():
            pts = [(float(r["seconds"]) / fine, float(r["error"])) for r in mine if r["model"] == model]
            if pts:
                ax.plot([a for a, _ in pts], [e for _, e in pts], marker, color=colour, mfc="none", ms=6)
    ax.axvline(1.0, color="0.4", lw=1, ls="--")
    ax.text(1.02, 0.97, "fine solve", transform=ax.get_xaxis_transform(), va="top", fontsize=8, color="0.3")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("time / fine Newton time")
    ax.set_ylabel("mean vertex error / longest side (thesis 2.5.2)")
    ax.set_title("Adaptive coarsening at several targets (dots); uniform DDFEM level 2 (squares),\n"
                 "level 1 (triangles), naive level 2 (x) and level 1 (+)", fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, ncol=2)
    fig.tight_layout()
    fig.savefig(sys.argv[2], dpi=110)


if __name__ == "__main__":
    main()

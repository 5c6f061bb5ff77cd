"""Error against time per scene for adaptive coarsening (tools/bench_adaptive.sh).

    python3 tools/plot_adaptive.py adaptive.csv out.png
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


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
        l2 = [(float(r["seconds"]) / fine, float(r["error"])) for r in mine if r["model"] == "level2"]
        if ad:
            ax.plot([a for a, _ in ad], [e for _, e in ad], "o-", color=colour, label=scene)
        if l2:
            ax.plot([a for a, _ in l2], [e for _, e in l2], "s", color=colour, mfc="none")
    ax.axvline(1.0, color="0.4", lw=1, ls="--")
    ax.text(1.02, 0.97, "fine solve", transform=ax.get_xaxis_transform(), va="top", fontsize=8, color="0.3")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("time / fine Newton time")
    ax.set_ylabel("mean vertex error / longest side (thesis 2.5.2)")
    ax.set_title("Adaptive coarsening at several targets (dots), uniform level 2 (squares)", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, ncol=2)
    fig.tight_layout()
    fig.savefig(sys.argv[2], dpi=110)


if __name__ == "__main__":
    main()

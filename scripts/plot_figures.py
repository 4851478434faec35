#!/usr/bin/python3
"""Plots the rows of tests/bench/figures_bench (scripts/make-figures.sh runs both):

  plot_figures.py MSAE_TSV TIME_TSV OUT_DIR STAMP

writes OUT_DIR/msae-vs-noise.png (MSAE against the noise level, one panel per mesh: the noisy
input, the default auto mode, the paper's Table 1 row and the Laplacian filter; mean over the
seeds, the bars their range) and OUT_DIR/time-vs-faces.png (seconds against face count, log-log).
STAMP (the commit and the command) is printed under each figure. Debian's python3-matplotlib.
"""
import csv
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

STYLE = {  # method: (label, colour, marker)
    "noisy": ("noisy input", "#9aa3b8", "x"),
    "auto": ("auto (the default)", "#1f6fb2", "o"),
    "paper": ("paper's Table 1 row (mode manual)", "#d9822b", "s"),
    "laplacian": ("Laplacian, best iteration count (oracle)", "#4c9a5a", "^"),
}


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f, delimiter="\t"))


def stamp(fig, text):
    fig.text(0.01, 0.005, text, fontsize=6.5, color="#666666", ha="left", va="bottom")


def msae_figure(data, out, text):
    meshes = list(dict.fromkeys(r["mesh"] for r in data))
    fig, axes = plt.subplots(1, len(meshes), figsize=(5.2 * len(meshes), 4.2), squeeze=False)
    for ax, mesh in zip(axes[0], meshes):
        faces = next(r["faces"] for r in data if r["mesh"] == mesh)
        for method, (label, colour, marker) in STYLE.items():
            by_sigma = defaultdict(list)
            for r in data:
                if r["mesh"] == mesh and r["method"] == method:
                    by_sigma[float(r["sigma"])].append(float(r["msae"]))
            if not by_sigma:
                continue
            sigmas = sorted(by_sigma)
            mean = [sum(by_sigma[s]) / len(by_sigma[s]) for s in sigmas]
            low = [m - min(by_sigma[s]) for m, s in zip(mean, sigmas)]
            high = [max(by_sigma[s]) - m for m, s in zip(mean, sigmas)]
            ax.errorbar(sigmas, mean, yerr=[low, high], label=label, color=colour, marker=marker, ms=4, lw=1.4, capsize=2)
        ax.set_yscale("log")
        ax.set_title("%s (%s faces)" % (mesh, f"{int(faces):,}"), fontsize=10)
        ax.set_xlabel("noise sigma along the normal (x mean edge length)")
        ax.set_ylabel("MSAE (rad^2, lower is better)")
        ax.grid(True, which="both", alpha=0.25)
    axes[0][0].legend(fontsize=8, loc="lower right")
    fig.suptitle("Error after denoising against the noise level", fontsize=11)
    fig.tight_layout(rect=(0, 0.03, 1, 1))
    stamp(fig, text)
    fig.savefig(out, dpi=110)


def time_figure(data, out, text):
    fig, ax = plt.subplots(figsize=(5.6, 4.2))
    for method in ("auto", "paper"):
        label, colour, marker = STYLE[method]
        points = sorted((int(r["faces"]), float(r["seconds"])) for r in data if r["method"] == method)
        if not points:
            continue
        ax.plot([p[0] for p in points], [p[1] for p in points], label=label, color=colour, marker=marker, lw=1.4)
        for faces, seconds in points:
            ax.annotate("%.2g s" % seconds, (faces, seconds), textcoords="offset points", xytext=(4, -10), fontsize=7,
                        color=colour)
    meshes = ", ".join(dict.fromkeys(r["mesh"] for r in data))
    threads = ", ".join(dict.fromkeys(r["threads"] for r in data))
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("faces (%s, midpoint-subdivided)" % meshes)
    ax.set_ylabel("seconds per mesh (%s threads)" % threads)
    ax.set_title("Time against face count", fontsize=11)
    ax.grid(True, which="both", alpha=0.25)
    ax.legend(fontsize=8)
    fig.tight_layout(rect=(0, 0.04, 1, 1))
    stamp(fig, text)
    fig.savefig(out, dpi=110)


def main():
    if len(sys.argv) != 5:
        sys.exit(__doc__)
    msae_tsv, time_tsv, out_dir, text = sys.argv[1:]
    msae_figure(rows(msae_tsv), out_dir + "/msae-vs-noise.png", text)
    time_figure(rows(time_tsv), out_dir + "/time-vs-faces.png", text)


if __name__ == "__main__":
    main()

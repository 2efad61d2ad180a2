"""Writes docs/accuracy_skinning.png: the decode error of a box whose vertices carry different
bone weights, against the weight spread, under a 40 degree joint turn (bench/bench_skinning.py
defines the box and computes the error; this script only plots it).

Usage: PYTHONPATH=addon python3 -m scripts.skinning_accuracy_plot [OUT.png]
"""
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
from bench import bench_skinning  # noqa: E402

out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(HERE, "..", "docs", "accuracy_skinning.png")
spreads = np.linspace(0.0, 0.5, 51)
fig, ax = plt.subplots(figsize=(5.0, 3.2), dpi=100)
for name, mean in bench_skinning.MEAN_WEIGHTS.items():
    ax.plot(spreads, [bench_skinning.nonrigid_error(s, mean(s)) for s in spreads], label=f"weights {name}")
ax.set_xlabel("weight spread s inside the box")
ax.set_ylabel("decode error / half-extent")
ax.set_ylim(0.0, None)
ax.grid(alpha=0.3)
ax.set_title("1 x 0.6 x 0.2 box across a joint turned 40 degrees", fontsize=10)
ax.legend(fontsize=7)
fig.tight_layout()
fig.savefig(out)
print("skinning_accuracy_plot: wrote", out)

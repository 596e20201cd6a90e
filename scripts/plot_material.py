#!/usr/bin/env python3
"""Plot a sinew-material CSV: J and the smallest raw/projected Hessian eigenvalue against the load."""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(csv_path, png_path, title=""):
    with open(csv_path, newline="") as f:
        rows = list(csv.DictReader(f))
    t = [float(r["stretch"]) for r in rows]
    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 4))
    a.plot(t, [float(r["J"]) for r in rows])
    a.set_xlabel("load parameter")
    a.set_ylabel("J = det F")
    a.grid(True)
    b.plot(t, [float(r["min_eig_raw"]) for r in rows], label="raw Hessian")
    b.plot(t, [float(r["min_eig_projected"]) for r in rows], label="projected")
    b.set_xlabel("load parameter")
    b.set_ylabel("smallest eigenvalue")
    b.legend()
    b.grid(True)
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(png_path, dpi=100)


if __name__ == "__main__":
    main(*sys.argv[1:4])

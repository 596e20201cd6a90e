"""Checks a finished run's physics against the numbers the README states (not only that it exited 0):
totals of Newton iterations, the final min J and volume change, no inverted point at any step, and how
far the flesh at the far end turned about an axis through a pivot.
Usage: check_run.py RESULTS_DIR [--newton LO HI] [--min-j LO HI] [--volume-percent LO HI]
                    [--turn-degrees LO HI --pivot X Y Z --axis X Y Z --toward X Y Z]
                    [--rise-mm LO HI --rise-x X0 X1] [--last COLUMN LO HI]
"""
import argparse
import csv
import glob
import os

import h5py
import numpy as np

ap = argparse.ArgumentParser()
ap.add_argument("results")
ap.add_argument("--newton", nargs=2, type=float)
ap.add_argument("--min-j", nargs=2, type=float)
ap.add_argument("--volume-percent", nargs=2, type=float)
ap.add_argument("--turn-degrees", nargs=2, type=float)
ap.add_argument("--pivot", nargs=3, type=float)
ap.add_argument("--axis", nargs=3, type=float)
ap.add_argument("--toward", nargs=3, type=float, help="the far tenth is taken along this direction from the pivot")
ap.add_argument("--rise-mm", nargs=2, type=float, help="how far the top (largest z) of the nodes with x in --rise-x rose")
ap.add_argument("--rise-x", nargs=2, type=float)
ap.add_argument("--last", nargs=3, action="append", default=[], metavar=("COLUMN", "LO", "HI"),
                help="a log.csv column's value at the last step")
a = ap.parse_args()


def within(name, value, bounds):
    lo, hi = bounds
    assert lo <= value <= hi, f"{name} = {value:.6g}, expected within [{lo}, {hi}]"
    print(f"{name} = {value:.6g} in [{lo}, {hi}]")


rows = list(csv.DictReader(open(os.path.join(a.results, "log.csv"))))
assert rows, "empty log"
inverted = max(int(r["inverted_points"]) for r in rows)
assert inverted == 0, f"{inverted} inverted points at some step"
if a.newton:
    within("Newton iterations", sum(int(r["newton_iterations"]) for r in rows), a.newton)
if a.min_j:
    within("final min J", float(rows[-1]["min_J"]), a.min_j)
if a.volume_percent:
    within("final volume change %", 100.0 * (float(rows[-1]["volume_ratio"]) - 1.0), a.volume_percent)
if a.turn_degrees:
    last = sorted(glob.glob(os.path.join(a.results, "step_*.h5")))[-1]
    with h5py.File(os.path.join(a.results, "mesh.h5"), "r") as m, h5py.File(last, "r") as s:
        X, x = m["/coordinates"][...], s["/position"][...]
    p, n = np.array(a.pivot), np.array(a.axis) / np.linalg.norm(a.axis)
    # The tenth of the body farthest from the pivot along `toward` (the hand end of a forearm), turned
    # about the axis: each point's angle in the plane normal to it.
    R = X - p
    reach = R @ np.array(a.toward)
    far = reach >= np.quantile(reach, 0.9)
    r0, r1 = R[far] - np.outer(R[far] @ n, n), (x - p)[far] - np.outer((x - p)[far] @ n, n)
    angle = np.degrees(np.arctan2(np.einsum("ij,ij->i", np.cross(r0, r1), np.tile(n, (far.sum(), 1))),
                                  np.einsum("ij,ij->i", r0, r1)))
    within("median turn of the far tenth (degrees)", float(np.median(angle)), a.turn_degrees)
if a.rise_mm:
    last = sorted(glob.glob(os.path.join(a.results, "step_*.h5")))[-1]
    with h5py.File(os.path.join(a.results, "mesh.h5"), "r") as m, h5py.File(last, "r") as s:
        X, x = m["/coordinates"][...], s["/position"][...]
    band = (X[:, 0] >= a.rise_x[0]) & (X[:, 0] <= a.rise_x[1])
    within("rise of the top over x in [%g, %g] (mm)" % tuple(a.rise_x), 1000.0 * (x[band, 2].max() - X[band, 2].max()), a.rise_mm)
for column, lo, hi in a.last:
    assert column in rows[-1], f"log.csv has no column '{column}'"
    within(f"last {column}", float(rows[-1][column]), (float(lo), float(hi)))
print("physics as stated")

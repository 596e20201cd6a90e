#!/usr/bin/python3
"""scripts/sinew-anatomy sorts each Newton iteration into exactly one class: a results folder written
here with one iteration of each kind (and a known number of each) must come back with those counts,
the steps whose first guess was pulled back and those that were cut must be found from log.csv, and a
folder without newton.csv must end with a message naming the file and a non-zero exit."""
import os
import subprocess
import sys
import tempfile

here = os.path.dirname(os.path.abspath(__file__))
tool = os.path.join(here, "..", "scripts", "sinew-anatomy")

# step, residual, step_length, exact, step_bound -> the class the tool must give it (tolerance 1e-2,
# so the tail starts below 10).
ROWS = [
    (1, 500.0, 1.0, 0, "inf", "full, projected, opening"),
    (1, 50.0, 0.6, 0, "inf", "full, projected, opening"),
    (1, 5.0, 1.0, 1, "inf", "full, exact, tail"),
    (1, 0.5, 2.0, 2, "inf", "full, exact, tail"),   # 2: exact with every term's Hessian unprojected
    (2, 800.0, 0.25, 0, "0.25", "held, projected, opening"),   # at its bound
    (2, 700.0, 0.125, 0, "0.25", "held, projected, opening"),  # backtracked below its bound: still held
    (2, 9.0, 0.05, 1, "0.1", "held, exact, tail"),
    (2, 9.0, 0.0, 1, "inf", "redone, exact, tail"),
    (2, 8.0, 0.25, 0, "inf", "short, projected, tail"),
    (3, 20.0, 0.0, 0, "0.5", "redone, projected, opening"),    # step 0 wins over a bound
    (3, 20.0, 1.0, 1, "1.5", "full, exact, opening"),          # a bound past 1 held nothing
    (3, 2.0, 1.0, 1, "inf", "full, exact, tail"),
]


def write(folder):
    with open(os.path.join(folder, "newton.csv"), "w") as f:
        f.write("step,load,iteration,residual,cg_iterations,step_length,exact_hessian,direction_max,step_bound\n")
        for i, (s, r, l, e, b, _) in enumerate(ROWS):
            f.write(f"{s},{s / 3},{i + 1},{r},10,{l},{e},0.01,{b}\n")
        # A step whose solve started converged logs its residual as iteration 0: no iteration, no step.
        f.write("4,1,0,0.001,0,0,0,nan,inf\n")
    with open(os.path.join(folder, "log.csv"), "w") as f:
        f.write("step,load,cuts,newton_iterations,first_guess\n")
        f.write("0,0,0,0,1\n1,0.333,0,4,1\n2,0.667,1,5,0.25\n3,1,0,3,1\n")


def main():
    failures = []
    with tempfile.TemporaryDirectory() as d:
        write(d)
        out = subprocess.run([sys.executable, tool, d, "--steps"], capture_output=True, text=True)
        if out.returncode != 0:
            sys.exit(f"FAILED: sinew-anatomy exited {out.returncode}: {out.stderr}")
        text = out.stdout
        print(text)
        want = {}
        for row in ROWS:
            want[row[5]] = want.get(row[5], 0) + 1
        got = {}
        for line in text.splitlines():
            parts = line.split()
            if len(parts) >= 5 and parts[-1].endswith("%") and line.startswith("  ") and "," in line:
                got[" ".join(parts[:-2])] = int(parts[-2])
        for cls, n in want.items():
            if got.get(cls) != n:
                failures.append(f"class '{cls}': {got.get(cls)} iterations, expected {n}")
        for cls in got:
            if cls not in want:
                failures.append(f"class '{cls}' reported, but no iteration is of it")
        expect_lines = [
            f"Newton iterations: {len(ROWS)} in 3 steps",
            "held by the collision test (all)        3",
            "exact Hessian (all)                     6",
            "in steps with a pulled-back guess       5",
            "in steps that were cut                  5",
        ]
        for e in expect_lines:
            if e not in text:
                failures.append(f"missing: '{e}'")
        if "(1 step)" not in text.split("pulled-back guess")[1].splitlines()[0]:
            failures.append("the pulled-back guess is not counted as one step")
        # Step 2's line: 5 iterations, 2 exact, 3 held, 1 redone, its guess pulled back to 0.25, 1 cut.
        if not any(line.split()[:6] == ["2", "5", "2", "3", "1", "0.25"] for line in text.splitlines() if line[:1] == " " and line.split()):
            failures.append("step 2's line is not '2 5 2 3 1 0.25 1'")
        os.remove(os.path.join(d, "newton.csv"))
        out = subprocess.run([sys.executable, tool, d], capture_output=True, text=True)
        if out.returncode == 0 or "newton.csv" not in out.stderr:
            failures.append(f"a folder without newton.csv: exit {out.returncode}, message '{out.stderr.strip()}'")
    for f in failures:
        print("FAILED: " + f, file=sys.stderr)
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""The rig corpus of issue 40: every rigged, animated asset of Debian's assimp-testmodels, run as a new
user writes the scene (the file's bind pose as rest, default solver and bones, self contact on), to its
clip's end, quasi-static (one load step per frame at 24 fps) and with inertia (backward Euler, 24 fps).

    perf/rig_corpus.py --sinew build/sinew --out results/perf/rigs [--only NAME,...] [--modes M,...] [--quick] [--check]

Prints one line per run (frames done, Newton and CG per frame, seconds per frame, inverted points,
deepest penetration, surface points inside elements where the mesh folds (no face crossed), surface
edges through a face (the surface through itself), volume change, and where the Newton iterations went:
the share whose step the contact barrier's collision test held short, the share in the tail (|F| below
1000 times the tolerance), and the steps whose first guess it pulled back with their share;
scripts/sinew-anatomy) and writes rigs.json and rigs.md in --out. --quick runs the first quarter of each
clip. --check (CTest rig_corpus_small) fails unless each run exits 0 after all its frames with no
inverted point at a frame end (quasi-static or with inertia), its deepest penetration below 0.05 cells
(the springs' thickness; the barrier's is 0.15), no surface edge through a face at a frame end, its
volume within 2% of the rest's, and newton.csv holding as many of the frames' Newton iterations as
log.csv counts."""
import argparse, csv, json, os, re, subprocess, sys, time
from importlib.machinery import SourceFileLoader

# scripts/sinew-anatomy: where each run's Newton iterations went (held by the collision test, the tail).
anatomy = SourceFileLoader("sinew_anatomy", os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scripts",
                                                          "sinew-anatomy")).load_module()

MODELS = "/usr/share/assimp/models"
BCN = MODELS + "/X/BCN_Epileptic.X"
MOCAP_MAP = ("Hips:B_Root_Pelvis_L, LeftUpLeg:B_Hip_Left, LeftLeg:B_Knee_Left, LeftFoot:B_Ankle_Left, "
             "RightUpLeg:B_Hip_Right, RightLeg:B_Knee_Right, RightFoot:B_Ankle_Right, LowerBack:B_Spine1, Spine:B_Spine2, "
             "Spine1:B_Spine4, Neck:B_Neck, LeftShoulder:B_Clavicle_Left, LeftArm:B_UpperArm_Left, "
             "LeftForeArm:B_ForeArm_Left, LeftHand:B_Hand_Left, RightShoulder:B_Clavicle_Right, RightArm:B_UpperArm_Right, "
             "RightForeArm:B_ForeArm_Right, RightHand:B_Hand_Right")

# name, rig file, clip, seconds (start, end), cell size (about 1/60 of the skin's largest extent, rounded),
# Skeleton extras. The cell size is the one entry a user must choose.
CLIPS = [
    ("huesitos", MODELS + "/FBX/huesitos.fbx", "", (0.0, 1.5625), 0.15, ""),
    ("animation_with_skeleton", MODELS + "/FBX/animation_with_skeleton.fbx", "", (0.0, 0.8333), 0.6, ""),
    ("bcn_epileptic", BCN, "", (0.0, 3.3), 0.03, ""),
    ("wuson_run", MODELS + "/X/Testwuson.X", "Wuson_Run", (0.0, 0.9667), 0.05, ""),
    ("wuson_walk", MODELS + "/X/Testwuson.X", "Wuson_Walk", (0.0, 3.6), 0.05, ""),
    ("bcn_mocap_jump", BCN, "", (1.0, 3.0), 0.03,
     '<Parameter name="Retarget from" type="string" value="%s/BVH/01_01.bvh"/>'
     '<Parameter name="Joint map" type="string" value="%s"/>' % (MODELS, MOCAP_MAP)),
]


def scene(name, rig, clip, span, cell, extra, dynamic, frames, out, model=""):
    start, end = span
    skeleton = ('<Parameter name="Rig" type="string" value="%s"/>' % rig +
                ('<Parameter name="Clip" type="string" value="%s"/>' % clip if clip else "") +
                '<Parameter name="Clip start" type="double" value="%g"/><Parameter name="Clip end" type="double" value="%g"/>'
                % (start, end) + extra)
    time_or_steps = ('<ParameterList name="Time"><Parameter name="Integrator" type="string" value="backward-euler"/>'
                     '<Parameter name="Frames" type="int" value="%d"/></ParameterList>' % frames if dynamic else
                     '<ParameterList name="Loading"><Parameter name="Steps" type="int" value="%d"/></ParameterList>' % frames)
    model_entry = '<Parameter name="Self contact model" type="string" value="%s"/>' % model if model else ""
    return f'''<ParameterList name="Sinew">
  <Parameter name="Scene" type="string" value="{name}"/>
  <ParameterList name="Mesh"><Parameter name="Type" type="string" value="rig"/>
    <Parameter name="Rig" type="string" value="{rig}"/><Parameter name="Cell size" type="double" value="{cell}"/></ParameterList>
  <ParameterList name="Material"><Parameter name="Model" type="string" value="stable-neohookean"/>
    <Parameter name="Young modulus" type="double" value="2.0e4"/><Parameter name="Poisson ratio" type="double" value="0.45"/></ParameterList>
  {time_or_steps}
  <ParameterList name="Skeleton">{skeleton}</ParameterList>
  <ParameterList name="Contact"><Parameter name="Self contact" type="bool" value="true"/>{model_entry}</ParameterList>
  <ParameterList name="Output"><Parameter name="Directory" type="string" value="{out}"/>
    <Parameter name="Checkpoint every" type="int" value="0"/><Parameter name="Skin glTF" type="bool" value="false"/><Parameter name="Skin PC2" type="bool" value="false"/><Parameter name="Surface OBJ" type="bool" value="false"/></ParameterList>
</ParameterList>
'''


def where_iterations_went(folder, rows, tolerance):
    # The frames' Newton iterations by class (sinew-anatomy; the run-up's, step 0, left out), and whether
    # newton.csv holds as many as log.csv counts.
    if not os.path.exists(os.path.join(folder, "newton.csv")):
        return {"held": 0, "tail": 0, "pulled_back_steps": 0, "pulled_back_iterations": 0, "newton_rows": 0}
    steps = {int(r["step"]) for r in rows}
    per = [v for k, v in anatomy.anatomy(folder, tolerance)["per_step"].items() if k in steps]
    pulled = [v for v in per if v.get("first_guess", 1.0) < 1.0]
    return {"held": sum(v["held"] for v in per), "tail": sum(v["tail"] for v in per), "pulled_back_steps": len(pulled),
            "pulled_back_iterations": sum(v["iterations"] for v in pulled),
            "newton_rows": sum(v["iterations"] for v in per)}


def summarize(log_csv, frames, tolerance=1e-2):
    # One log row per frame: a quasi-static load step, or a time step at the default one substep.
    rows = list(csv.DictReader(open(log_csv))) if os.path.exists(log_csv) else []
    rows = [r for r in rows if int(r["step"]) > 0]
    done = len(rows)
    went = where_iterations_went(os.path.dirname(log_csv), rows, tolerance)
    n = [int(r["newton_iterations"]) for r in rows] or [0]
    c = [int(r["cg_iterations"]) for r in rows] or [0]
    s = [float(r["seconds_total"]) for r in rows] or [0.0]
    return {
        "frames": frames, "done": done,
        "newton_avg": sum(n) / max(1, done), "newton_max": max(n),
        "cg_avg": sum(c) / max(1, done), "seconds_avg": sum(s) / max(1, done),
        "inverted_max": max([int(r["inverted_points"]) for r in rows] or [0]),
        "min_J": min([float(r["min_J"]) for r in rows] or [1.0]),
        # A spring's sample behind its target, or a surface point found through a face by the step's
        # last detection with no spring pushing it out yet (crossed_depth): both are penetration. A
        # point inside an element that the surface does not enclose went through no face: counted apart
        # (inside_folded; logs older than that column have inside_depth, which counts both).
        "penetration_max": max([max(float(r.get("penetration") or 0.0), float(r.get("crossed_depth", r.get("inside_depth")) or 0.0))
                                for r in rows] or [0.0]),
        "folded_max": max([int(float(r.get("inside_folded") or 0)) for r in rows] or [0]),
        # Surface edges through a face at a frame end: the surface through itself, which the points'
        # winding numbers miss where two edges cross (logs older than the column: 0).
        "crossings_max": max([int(float(r.get("edges_through_faces") or 0)) for r in rows] or [0]),
        "crossing_frames": sum(1 for r in rows if float(r.get("edges_through_faces") or 0) > 0),
        "volume_change_max": max([abs(float(r["volume_ratio"]) - 1.0) for r in rows] or [0.0]),
        "newton_total": sum(n) if rows else 0,
        **went,
    }


def share(n, total):
    return f"{100.0 * n / total:.0f}%" if total else "-"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sinew", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--only", default="")
    ap.add_argument("--modes", default="quasi-static,dynamic")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--timeout", type=float, default=1800.0)
    ap.add_argument("--check", action="store_true")
    ap.add_argument("--model", default="", help="'Self contact model' (springs, barrier); default: Sinew's own")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    results = []
    for name, rig, clip, span, cell, extra in CLIPS:
        if a.only and name not in a.only.split(","):
            continue
        if not os.path.exists(rig):
            print(f"{name}: {rig} is missing (apt-get install assimp-testmodels)", file=sys.stderr)
            continue
        if a.quick:
            span = (span[0], span[0] + 0.25 * (span[1] - span[0]))
        frames = max(1, round((span[1] - span[0]) * 24))
        for mode in a.modes.split(","):
            dynamic = mode == "dynamic"
            out = os.path.join(a.out, f"{name}_{mode}")
            xml = os.path.join(a.out, f"{name}_{mode}.xml")
            open(xml, "w").write(scene(name, rig, clip, span, cell, extra, dynamic, frames, out, a.model))
            t0 = time.time()
            with open(os.path.join(a.out, f"{name}_{mode}.log"), "w") as log:
                try:
                    rc = subprocess.run([a.sinew, xml], stdout=log, stderr=subprocess.STDOUT, timeout=a.timeout).returncode
                except subprocess.TimeoutExpired:
                    rc = "timeout"
            text = open(os.path.join(a.out, f"{name}_{mode}.log")).read()
            # The header's "converged when |F| < X": the tolerance the tail is measured against.
            m = re.search(r"converged when \|F\| < ([0-9.eE+-]+)", text)
            r = summarize(os.path.join(out, "log.csv"), frames, float(m.group(1)) if m else 1e-2)
            r.update({"clip": name, "mode": mode, "exit": rc, "wall": time.time() - t0, "cell": cell})
            for line in text.splitlines():
                if line.startswith("  mesh: "):
                    r["mesh"] = line[8:]
                if line.startswith("  skeleton: "):
                    r["skeleton"] = line[12:]
            results.append(r)
            print(f"{name:24s} {mode:12s} exit {rc!s:7s} frames {r['done']}/{frames}  Newton/frame {r['newton_avg']:.1f} "
                  f"(max {r['newton_max']})  CG/frame {r['cg_avg']:.0f}  s/frame {r['seconds_avg']:.2f}  inverted {r['inverted_max']}  "
                  f"min J {r['min_J']:.3g}  penetration {r['penetration_max']:.3g}  in folds {r['folded_max']}  "
                  f"edges through faces {r['crossings_max']} ({r['crossing_frames']} frames)  volume {100 * r['volume_change_max']:.2f}%  "
                  f"held {share(r['held'], r['newton_total'])}  tail {share(r['tail'], r['newton_total'])}  "
                  f"pulled-back guesses {r['pulled_back_steps']} ({share(r['pulled_back_iterations'], r['newton_total'])})", flush=True)
    json.dump(results, open(os.path.join(a.out, "rigs.json"), "w"), indent=1)
    failed = []
    for r in results if a.check else []:
        what = f"{r['clip']} {r['mode']}"
        if r["exit"] != 0 or r["done"] != r["frames"]:
            failed.append(f"{what}: exit {r['exit']} after {r['done']} of {r['frames']} frames")
        if r["inverted_max"] > 0:
            failed.append(f"{what}: {r['inverted_max']} inverted points at a frame end")
        if not r["penetration_max"] < 0.05 * r["cell"]:
            failed.append(f"{what}: penetration {r['penetration_max']:.3g} not below the thickness {0.05 * r['cell']:.3g}")
        if r["crossings_max"] > 0:
            failed.append(f"{what}: {r['crossings_max']} surface edges through a face at a frame end ({r['crossing_frames']} frames)")
        if not r["volume_change_max"] < 0.02:
            failed.append(f"{what}: volume changed by {100 * r['volume_change_max']:.2f}%")
        if r["newton_rows"] != r["newton_total"]:
            failed.append(f"{what}: newton.csv has {r['newton_rows']} Newton iterations of the frames, log.csv counts {r['newton_total']}")
    for f in failed:
        print("FAILED: " + f, file=sys.stderr)
    if failed:
        sys.exit(1)
    with open(os.path.join(a.out, "rigs.md"), "w") as md:
        md.write("| clip | run | exit | frames | Newton/frame (max) | CG/frame | s/frame | inverted at frame ends | min J | deepest penetration | points in folded elements | surface edges through a face (frames) | volume change | held by contact | tail | pulled-back guesses (their iterations) |\n")
        md.write("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n")
        for r in results:
            md.write(f"| {r['clip']} | {r['mode']} | {r['exit']} | {r['done']}/{r['frames']} | {r['newton_avg']:.1f} ({r['newton_max']}) | "
                     f"{r['cg_avg']:.0f} | {r['seconds_avg']:.2f} | {r['inverted_max']} | {r['min_J']:.3g} | {r['penetration_max']:.3g} | "
                     f"{r['folded_max']} | {r['crossings_max']} ({r['crossing_frames']}) | {100 * r['volume_change_max']:.2f}% | {share(r['held'], r['newton_total'])} | "
                     f"{share(r['tail'], r['newton_total'])} | {r['pulled_back_steps']} ({share(r['pulled_back_iterations'], r['newton_total'])}) |\n")


if __name__ == "__main__":
    main()

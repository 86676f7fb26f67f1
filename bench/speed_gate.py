"""The speed gate (issue 49): instruction counts of the tracer and of a mesh build, compared with a
checked-in baseline, so that a slowdown fails CI instead of being found weeks later.

Counts, under ``valgrind --tool=callgrind`` (deterministic: one thread, fixed scenes, the same
build gives the same counts whatever the machine's load), the instructions of

* ``trace <scene> 32³``: one trace of each 4D bench scene (``bench/scenes``: copies of
  tesseract48, s3_3072 and elev_3072 of the shared bench; shaded, a directional light with
  shadows, two-sided) at a 32³ retina, after a first trace (the steady state, as
  ``bench/ab.py`` times it);
* ``build ico6``: loading a mid-size mesh, the 81,920-triangle icosphere as numpy arrays
  through the builder with a directional light (``Scene.compiled()``: validation, orientation
  check, prepared simplices, BVH, and what the light needs);
* ``first trace ico6 32²``: its first trace.

Each count is what ran between two marks around the Python call (``RAYON_NUM_THREADS=1``,
``threads=1``); it is compared with the baseline of ``bench/speed_gate.json`` recorded for
this kind of machine (the key ``<arch>-avx2`` or ``<arch>-portable``: the kernels the tracer
picks at run time; valgrind hides AVX-512, so every AVX2 machine counts the AVX2 kernels, and
the build is generic x86-64 without ``target-cpu=native``). The gate fails when

* a count exceeds its baseline by more than 3 %;
* the baseline file changed since the merge base with ``$SPEED_GATE_BASE`` (default
  ``origin/main``, else ``main``) and no line added to ``CHANGELOG.md`` in that diff names
  ``bench/speed_gate.json`` (saying why the counts moved);
* there is no baseline for this machine's key (record one with ``--update``).

A count more than 3 % below its baseline is reported, so that the baseline can be lowered
(``--update``) and the gain kept. Other differences from the baseline's recorded environment
(rustc through the wheel, valgrind's version, Python's) are printed: they can move counts by
themselves.

Usage:  python bench/speed_gate.py [--update] [--python PYTHON] [--json]
  (``.ci/speed-gate`` installs valgrind if needed and runs it with the tests' interpreter.)
"""

from __future__ import annotations

import argparse
import glob
import json
import os
import platform
import re
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
BASELINE = os.path.join(HERE, "speed_gate.json")
TOLERANCE = 0.03
SCENES = ["tesseract48", "s3_3072", "elev_3072"]
RES = 32

# Runs in the measured process. `os.getppid()` (libc's getppid, which nothing else calls)
# marks the operations: callgrind dumps its counts when it is entered (--dump-before), so each
# count is what ran between two marks, in every thread: the operation and a few thousand
# instructions of the Python call around it. This needs no symbols of the extension (the
# wheel is stripped).
CHILD = r"""
import os, sys, warnings
sys.path.insert(0, sys.argv[1])
import numpy as np
from trace import icosphere
import ndtrace
here, scenes, res = sys.argv[1], sys.argv[2].split(","), int(sys.argv[3])
mark = os.getppid
warnings.simplefilter("ignore")

def scene_4d(name):
    d = np.load(os.path.join(here, "scenes", name + ".npz"))
    return {
        "dim": 4, "background": d["background"].tolist(), "ambient": d["ambient_light"].tolist(),
        "camera": {"position": d["camera_position"].tolist(),
                   "orientation": d["camera_orientation"].tolist(),
                   "fov": float(d["fov_degrees"]), "resolution": res},
        "lights": [{"type": "directional", "direction": d["light_direction"].tolist(),
                    "color": d["light_color"].tolist()}],
        "objects": [{"shape": "mesh", "vertices": d["vertices"], "simplices": d["simplices"],
                     "material": {"color": d["material_color"].tolist(),
                                  "ambient": np.asarray(d["material_ambient"]).tolist(),
                                  "specular": np.asarray(d["material_specular"]).tolist(),
                                  "shininess": float(d["material_shininess"])}}],
        "render": {"two_sided": True, "cull_backfaces": False, "shadows": True},
    }

v, f = icosphere(6)
f = f.astype(np.int64)
eye = (2.6 * np.array([0.3, 0.4, 1.0]) / np.linalg.norm([0.3, 0.4, 1.0])).tolist()
descs = [scene_4d(name) for name in scenes]
ico = (ndtrace.Scene(3)
       .set_camera(position=eye, look_at=[0, 0, 0], up=[0, 1, 0], fov=45, resolution=res)
       .add_light("directional", direction=[0.3, 0.5, 0.8])
       .add_object("mesh", vertices=v, simplices=f))
ndtrace.trace(ndtrace.load_dict(scene_4d(scenes[0])), threads=1)  # every first-call cost
mark()                                       # what ran before: not counted
for d in descs:
    s = ndtrace.load_dict(d)
    mark()                                   # build (not compared)
    ndtrace.trace(s, threads=1)
    mark()                                   # first trace (not compared)
    ndtrace.trace(s, threads=1)
    mark()                                   # steady trace
ico.compiled()
mark()                                       # build ico6
ndtrace.trace(ico, threads=1)
mark()                                       # first trace ico6
"""


def labels() -> list[tuple[str, bool]]:
    """The dumps of CHILD in order: (label, compared)."""
    out = []
    for name in SCENES:
        out += [(f"build {name}", False), (f"first trace {name} {RES}³", False),
                (f"trace {name} {RES}³", True)]
    return out + [("build ico6", True), (f"first trace ico6 {RES}²", True)]


def environment(python: str) -> dict:
    """What the counts depend on besides the code: recorded with a baseline, compared on a run."""
    probe = ("import platform, ndtrace; print(getattr(ndtrace, '__version__', '?')); "
             "print(platform.python_version())")
    version, py = subprocess.run([python, "-c", probe], check=True, capture_output=True,
                                 text=True).stdout.split()
    flags = open("/proc/cpuinfo").read() if os.path.exists("/proc/cpuinfo") else ""
    valgrind = subprocess.run(["valgrind", "--version"], capture_output=True,
                              text=True).stdout.strip() if shutil.which("valgrind") else None
    return {"ndtrace": version, "python": py, "valgrind": valgrind,
            "machine": platform.machine(), "avx2": " avx2" in flags}


def key(env: dict) -> str:
    """The baseline a machine is compared with: its architecture and the kernels it runs."""
    return f"{env['machine']}-{'avx2' if env['avx2'] else 'portable'}"


def measure(python: str) -> dict[str, int]:
    """The instruction counts of the compared operations of `labels`."""
    if shutil.which("valgrind") is None:
        sys.exit("speed-gate: valgrind is not installed (apt-get install valgrind)")
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "cg.out")
        env = dict(os.environ, RAYON_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1",
                   OMP_NUM_THREADS="1", PYTHONHASHSEED="0")
        cmd = ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}",
               "--dump-before=getppid", python, "-c", CHILD, HERE, ",".join(SCENES), str(RES)]
        r = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=tmp)
        if r.returncode != 0:
            sys.exit(f"speed-gate: the measured run failed:\n{r.stderr[-4000:]}")
        parts = sorted(glob.glob(out + ".*"), key=lambda p: int(p.rsplit(".", 1)[1]))
        counts = []
        for p in parts:
            text = open(p).read()
            if "getppid" not in (re.search(r"^desc: Trigger: (.*)$", text, re.M) or [""])[0]:
                continue
            m = re.search(r"^(?:summary|totals): (\d+)", text, re.M)
            counts.append(int(m.group(1)) if m else 0)
        # The first mark ends what ran before the operations.
        counts = counts[1:]
    want = labels()
    if len(counts) != len(want):
        sys.exit(f"speed-gate: expected {len(want)} marks, got {len(counts)}")
    return {label: c for (label, compared), c in zip(want, counts) if compared}


def compare(counts: dict[str, int], baseline: dict[str, int],
            tol: float = TOLERANCE) -> tuple[list[str], list[str]]:
    """The failures of `counts` against `baseline` (a count above it by more than `tol`, a count
    missing on either side) and the table's lines."""
    failed, lines = [], [f"{'operation':<28} {'baseline':>13} {'now':>13} {'change':>8}"]
    for label, now in counts.items():
        was = baseline.get(label)
        if was is None:
            failed.append(f"{label}: not in the baseline (record it with --update)")
            lines.append(f"{label:<28} {'—':>13} {now:>13,}")
            continue
        change = now / was - 1
        flag = ""
        if change > tol:
            failed.append(f"{label}: {change:+.1%} instructions")
            flag = "  FAIL"
        elif change < -tol:
            flag = "  (below the baseline: lower it with --update)"
        lines.append(f"{label:<28} {was:>13,} {now:>13,} {change:>+8.1%}{flag}")
    for label in baseline:
        if label not in counts:
            failed.append(f"{label}: in the baseline but not measured")
    return failed, lines


def git(root: str, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run(["git", "-C", root, *args], capture_output=True, text=True)


def merge_base(root: str) -> str | None:
    for ref in filter(None, [os.environ.get("SPEED_GATE_BASE"), "origin/main", "main"]):
        r = git(root, "merge-base", "HEAD", ref)
        if r.returncode == 0:
            return r.stdout.strip()
    return None


def baseline_change_explained(root: str = ROOT, baseline: str = BASELINE) -> tuple[bool, str]:
    """(unexplained, note): whether the baseline file differs from the merge base (committed or
    not) with no line added to CHANGELOG.md in the same diff that names it."""
    base = merge_base(root)
    if base is None:
        return False, "no merge base found (not a git checkout, or no main): baseline taken as is"
    rel = os.path.relpath(baseline, root)
    untracked = git(root, "ls-files", "--error-unmatch", "--", rel).returncode != 0
    if not untracked and git(root, "diff", "--quiet", base, "--", rel).returncode == 0:
        return False, f"baseline unchanged since the merge base {base[:10]}"
    diff = git(root, "diff", base, "--", "CHANGELOG.md").stdout.splitlines()
    named = [l for l in diff if l.startswith("+") and not l.startswith("+++") and rel in l]
    if not named:
        return True, (f"{rel} changed since the merge base {base[:10]}, but no line added to "
                      f"CHANGELOG.md names it: say there why the counts moved")
    return False, f"{rel} changed since the merge base {base[:10]}; CHANGELOG.md: {named[0][1:].strip()[:100]}"


def update(counts: dict[str, int], env: dict, path: str = BASELINE) -> None:
    """Records `counts` as the baseline of `env`'s key (the other keys' are kept)."""
    data = {"about": "Instruction counts of bench/speed_gate.py (callgrind), per kind of machine; "
                     "a change of this file needs a CHANGELOG.md line naming it.",
            "tolerance": TOLERANCE, "baselines": {}}
    if os.path.exists(path):
        data = json.load(open(path))
    data["baselines"][key(env)] = {"environment": env, "counts": counts}
    with open(path, "w") as f:
        json.dump(data, f, indent=1, ensure_ascii=False)
        f.write("\n")


def gate(counts: dict[str, int], env: dict, root: str = ROOT,
         path: str = BASELINE) -> tuple[bool, list[str]]:
    """(passed, report): `counts` measured on `env` against the baseline file at `path`."""
    data = json.load(open(path))
    unexplained, note = baseline_change_explained(root, path)
    report, failed = [f"speed-gate: {note}"], []
    if unexplained:
        failed.append("baseline changed without a CHANGELOG.md line")
    recorded = data["baselines"].get(key(env))
    if recorded is None:
        failed.append(f"no baseline for {key(env)} (have {sorted(data['baselines'])}): record "
                      f"one with --update")
        recorded = {"environment": {}, "counts": {}}
    diffs = {k: v for k, v in recorded["environment"].items()
             if env.get(k) != v and k != "ndtrace"}
    if diffs:
        report.append(f"speed-gate: the baseline was recorded with {diffs}, this run has "
                      f"{ {k: env.get(k) for k in diffs} }: counts may differ for that reason alone")
    tol = data.get("tolerance", TOLERANCE)
    more, lines = compare(counts, recorded["counts"], tol)
    failed += more
    report += lines
    if failed:
        report.append("speed-gate: FAILED: " + "; ".join(failed) + f" (tolerance {tol:.0%}; an "
                      "intended change updates bench/speed_gate.json with --update and says why "
                      "in CHANGELOG.md)")
    else:
        report.append("speed-gate: passed")
    return not failed, report


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--python", default=sys.executable, help="the interpreter whose ndtrace is measured")
    ap.add_argument("--update", action="store_true", help="record the counts measured in bench/speed_gate.json")
    ap.add_argument("--json", action="store_true", help="print the counts as JSON")
    a = ap.parse_args()
    env = environment(a.python)
    counts = measure(a.python)
    if a.json:
        print(json.dumps(counts, indent=1, ensure_ascii=False))
    if a.update:
        update(counts, env)
        print(f"speed-gate: recorded the counts of {key(env)} in "
              f"{os.path.relpath(BASELINE, ROOT)}; add a CHANGELOG.md line naming it and saying "
              f"why the counts moved")
        return 0
    passed, report = gate(counts, env)
    print("\n".join(report))
    return 0 if passed else 1


if __name__ == "__main__":
    sys.exit(main())

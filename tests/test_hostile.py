"""Hostile files and hard stops (issue 24): no input may kill the process.

The files in tests/data/bad/ are written by tests/data/bad/make.py; README.md there lists the
error each must give. Every test here would have aborted the interpreter (exit 134), raised a
PanicException, or returned a NaN picture before the fixes.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

import ndtrace

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BAD = os.path.join(ROOT, "tests", "data", "bad")

# -- files: each hand-made bad file and the error it must give ------------------------

BAD_FILES = {
    "exr-data-window.exr": "reading its samples needs about",
    "exr-truncated.exr": "bytes of uncompressed samples, the file has",
    "retina-shape.exr": "ndtrace.retinaShape (100000,100000,100000) does not match its 1 parts of 7 × 1 cells",
    "retina-object-id.exr": "objectId 2147483653 is out of range",
    "retina-dim.exr": "ndtrace.dim = -3 is not in 2..=8",
}


@pytest.mark.parametrize("name", sorted(BAD_FILES))
def test_each_bad_file_gives_its_error(name):
    path = os.path.join(BAD, name)
    with pytest.raises(OSError) as e:
        ndtrace.read_exr(path)
    assert str(e.value).startswith(path + ": ") and BAD_FILES[name] in str(e.value), str(e.value)
    assert "\n" not in str(e.value)


def test_every_bad_file_is_listed_in_the_readme():
    readme = open(os.path.join(BAD, "README.md")).read()
    files = sorted(f for f in os.listdir(BAD) if not f.endswith((".md", ".py")))
    assert files == sorted(BAD_FILES)
    for name, message in BAD_FILES.items():
        assert f"`{name}`" in readme and message in readme, name


def _in_subprocess(code: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True,
                          text=True, cwd=ROOT, timeout=120)


def test_readers_under_a_4_gb_address_space_limit_raise_cleanly():
    # The address-space limit, not free RAM, is what binds here; a too-large request must be
    # refused (one line) instead of aborting in the allocator (exit 134).
    p = _in_subprocess(f"""
        import resource
        import numpy as np
        import ndtrace
        resource.setrlimit(resource.RLIMIT_AS, (4 << 30, 4 << 30))
        for name in ("exr-data-window.exr", "retina-shape.exr"):
            try:
                ndtrace.read_exr({BAD!r} + "/" + name)
            except OSError as e:
                print("refused:", e)
        # 3.2 GB of float32 samples fit in RAM but not under the limit.
        import struct, sys
        sys.path.insert(0, {BAD!r})
        import make
        data = open({BAD!r} + "/exr-data-window.exr", "rb").read()
        open("/tmp/ndtrace-rlimit-{os.getpid()}.exr", "wb").write(make.patch_windows(data, 19999, 9999))
        try:
            ndtrace.read_exr("/tmp/ndtrace-rlimit-{os.getpid()}.exr")
        except OSError as e:
            print("refused:", e)
        # A retina too large for the limit is refused when the scene is built.
        d = {{"dim": 4, "camera": {{"position": [0, 0, 0, 4], "look_at": [0, 0, 0, 0],
             "up": [[0, 1, 0, 0], [0, 0, 1, 0]], "fov": 50, "resolution": 600}},
             "objects": [{{"shape": "simplex"}}]}}
        try:
            ndtrace.load_dict(d)
        except ValueError as e:
            print("refused:", e)
    """)
    os.unlink(f"/tmp/ndtrace-rlimit-{os.getpid()}.exr")
    assert p.returncode == 0, p.stderr
    lines = p.stdout.splitlines()
    assert len(lines) == 4 and all(l.startswith("refused:") for l in lines), p.stdout
    assert "does not match its 1 parts" in lines[1], p.stdout
    assert all("more than this process can spare" in lines[k] for k in (0, 2, 3)), p.stdout
    assert "RLIMIT_AS" in lines[2] and "camera.resolution" in lines[3], p.stdout


def test_big_generated_shapes_and_fields_are_refused_before_they_are_built():
    # The scene fuzzer's first finding: `sphere subdivisions = 6` in 4D (12 582 912 simplices) under
    # a small memory cap ran for minutes building what the cap could not hold. The mesh and its
    # BVH are now counted against the guard before any of it is generated, as is an elevation
    # map's field; both refusals name the key.
    p = subprocess.run([sys.executable, "-c", textwrap.dedent("""
        import time
        import numpy as np
        import ndtrace
        cam = {"position": [0, 0, 0, 4], "look_at": [0, 0, 0, 0], "up": [[0, 1, 0, 0], [0, 0, 1, 0]],
               "fov": 50, "resolution": 8}
        for obj in ({"shape": "sphere", "subdivisions": 6},
                    {"shape": "elevation", "field": np.zeros((64, 64, 64))}):
            t = time.perf_counter()
            try:
                ndtrace.load_dict({"dim": 4, "camera": cam, "objects": [obj]})
                print("built")
            except ValueError as e:
                print(f"refused in {time.perf_counter() - t:.1f} s:", e)
    """)], capture_output=True, text=True, cwd=ROOT, timeout=120,
        env={**os.environ, "NDTRACE_MEMORY_LIMIT": "64M"})
    assert p.returncode == 0, p.stderr
    lines = p.stdout.splitlines()
    assert len(lines) == 2 and all(l.startswith("refused") for l in lines), p.stdout
    assert "objects[0].subdivisions" in lines[0] and "a sphere of 12582912 simplices" in lines[0], p.stdout
    assert "objects[0]: an elevation map of 262144 grid points" in lines[1] and "NDTRACE_MEMORY_LIMIT" in lines[1], p.stdout


def test_retina_exr_files_are_byte_reproducible(tmp_path):
    # The exr crate writes custom attributes in HashMap order; ndtrace sorts them, so two
    # processes (different hash seeds) write the same bytes.
    outs = []
    for k in range(2):
        ret = tmp_path / f"r{k}.exr"
        p = cli("scenes/tesseract.toml", "-o", str(tmp_path / f"t{k}.png"), "--retina", str(ret),
                "--resolution", "8", "--quiet")
        assert p.returncode == 0, p.stderr
        outs.append(ret.read_bytes())
    assert outs[0] == outs[1]
    r = ndtrace.read_exr(tmp_path / "r0.exr")
    ndtrace.write_exr(tmp_path / "again.exr", r)
    assert (tmp_path / "again.exr").read_bytes() == outs[0]


# -- the Python API: validation at the boundary ---------------------------------------


def _retina(**change) -> ndtrace.Retina:
    r = ndtrace.trace(ndtrace.load_toml(open(os.path.join(ROOT, "scenes", "cube.toml")).read()
                                        .replace("resolution = ", "resolution = 6 #"),
                                        base=os.path.join(ROOT, "scenes")))
    fields = {k: getattr(r, k) for k in ("dim", "rgba", "depth", "normal", "object_id", "primitive_id")}
    fields.update(change)
    return ndtrace.Retina(**fields, camera=r.camera)


@pytest.mark.parametrize("change, message", [
    # The retina's shape is its depth's: the other arrays are checked against it.
    (dict(depth=np.zeros((5, 6), np.float32)), "rgba: holds 144 values"),
    (dict(normal=np.zeros((6, 6, 4), np.float32)), "normal"),
    (dict(object_id=np.zeros((6, 5), np.int32)), "object_id"),
    (dict(primitive_id=np.zeros(35, np.int64)), "primitive_id: holds 35 values"),
    (dict(object_id=np.full((6, 6), -7, np.int32)), "object_id"),
    (dict(dim=-1), "dim"),
    (dict(dim=2**70), "dim"),
])
def test_write_exr_checks_a_retinas_arrays_against_each_other(tmp_path, change, message):
    try:
        r = _retina(**change)
    except ValueError as e:  # the Retina constructor may refuse it already
        assert message in str(e)
        return
    with pytest.raises(ValueError, match=message):
        ndtrace.write_exr(tmp_path / "r.exr", r)
    assert list(tmp_path.iterdir()) == []


def test_composite_refuses_non_finite_and_float32_overflow():
    rgba = np.full((4, 4, 4), 0.5, np.float32)
    with pytest.raises(ValueError, match="opacity.*overflows float32"):
        ndtrace.composite(rgba, opacity=1e39)
    with pytest.raises(ValueError, match="zoom.*overflows float32"):
        ndtrace.composite(rgba, zoom=1e300)
    bad = rgba.copy()
    bad[1, 2, 0] = np.nan
    with pytest.raises(ValueError, match=r"rgba: non-finite value NaN at index 24"):
        ndtrace.composite(bad)
    bad[1, 2, 0] = np.inf
    with pytest.raises(ValueError, match="rgba: non-finite value inf"):
        ndtrace.composite(bad)
    big = rgba.astype(np.float64)
    big[0, 0, 1] = 1e39
    with pytest.raises(ValueError, match="retina: value 1e[+]39 at index 1 overflows float32"):
        ndtrace.composite(big)
    # Faint cells under a large (representable) opacity stay finite.
    faint = rgba.copy()
    faint[..., 3] = 1e-30
    picture = ndtrace.composite(faint, opacity=1e30, size=(8, 8))
    assert np.isfinite(picture).all()


def test_integer_arguments_out_of_range_are_value_errors():
    with pytest.raises(ValueError, match="j: axis 18446744073709551616 is out of range"):
        ndtrace.rotation.plane(3, 0, 2**64, 0.1)
    with pytest.raises(ValueError, match="i: expected an axis number ≥ 0"):
        ndtrace.rotation.plane(3, -1, 2, 0.1)


def test_a_self_referencing_scene_is_a_value_error():
    d = {"dim": 3, "objects": []}
    d["objects"].append(d)
    with pytest.raises(ValueError, match=r"nested more than 32 levels deep"):
        ndtrace.load_dict(d)


def test_panics_become_internal_errors_that_the_suite_counts():
    assert issubclass(ndtrace.InternalError, RuntimeError)
    assert isinstance(ndtrace._ndtrace.internal_errors(), int)


# -- the command line ------------------------------------------------------------------


def cli(*args, **kw) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "ndtrace", *args], capture_output=True,
                          text=True, cwd=kw.pop("cwd", ROOT), timeout=kw.pop("timeout", 120), **kw)


SCRIPTS = {
    "syntax": ("def scene(:\n    pass\n", ":1:11: syntax error: ", None),
    "raises": ("import ndtrace\n\ndef scene():\n    return 1 / 0\n",
               ":4: scene() raised ZeroDivisionError: division by zero", None),
    "recursion": ("def f(k):\n    return f(k + 1)\n\ndef scene():\n    return f(0)\n",
                  ": scene() raised RecursionError: maximum recursion depth exceeded", None),
    "exits": ("import sys\n\ndef scene():\n    sys.exit(0)\n",
              ": scene() called sys.exit(0) instead of returning a scene", None),
    "module-exits": ("import sys\nsys.exit(3)\n",
                     ": running the script called sys.exit(3) instead of returning a scene", None),
}


@pytest.mark.parametrize("kind", sorted(SCRIPTS))
def test_py_scene_failures_are_one_line_naming_the_script(tmp_path, kind):
    text, message, _ = SCRIPTS[kind]
    script = tmp_path / f"{kind}.py"
    script.write_text(text)
    out = tmp_path / "o.png"
    p = cli(str(script), "-o", str(out))
    assert p.returncode == 2, p.stderr
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"ndtrace: error: {script}"), p.stderr
    assert message in lines[0], p.stderr
    assert not out.exists()
    d = cli(str(script), "-o", str(out), "--debug")
    assert d.returncode == 2 and "Traceback (most recent call last)" in d.stderr


def test_threads_are_capped_with_a_message(tmp_path):
    cores = os.cpu_count() or 1
    t = time.monotonic()
    p = cli("scenes/square.toml", "-o", str(tmp_path / "s.png"), "--threads", "100000")
    assert p.returncode == 0, p.stderr
    assert time.monotonic() - t < 60
    assert f"--threads 100000 capped at {4 * cores} (4 per core on {cores} cores)" in p.stderr


def test_the_same_path_for_two_outputs_is_refused(tmp_path):
    out = tmp_path / "x.exr"
    p = cli("scenes/cube.toml", "-o", str(out), "--retina", str(tmp_path / "." / "x.exr"))
    assert p.returncode == 2 and "the same file as -o" in p.stderr, p.stderr
    assert not out.exists()
    scene = tmp_path / "cube.toml"
    scene.write_text(open(os.path.join(ROOT, "scenes", "cube.toml")).read())
    p = cli(str(scene), "-o", str(tmp_path / "pic.png"), "--retina", str(scene))
    assert p.returncode == 2, p.stderr


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP])
def test_sigterm_and_sighup_clean_up_like_ctrl_c(tmp_path, sig):
    out = tmp_path / "spin.gif"
    proc = subprocess.Popen(
        [sys.executable, "-m", "ndtrace", "scenes/tesseract_spin.toml", "-o", str(out),
         "--resolution", "48", "--samples", "2", "--threads", "1", "--frames", "200"],
        cwd=ROOT, stderr=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    # The progress bar's first line: the video's temporary file exists and frames are traced.
    line = proc.stderr.readline()
    assert line.startswith("frames"), line
    time.sleep(1.0)
    assert proc.poll() is None
    proc.send_signal(sig)
    proc.wait(timeout=20)
    err = proc.stderr.read()
    assert proc.returncode == 128 + sig, err
    assert f"terminated by {signal.Signals(sig).name}" in err and "Traceback" not in err
    assert list(tmp_path.iterdir()) == []


def test_ctrl_c_during_start_up_exits_130_quietly():
    # SIGINT while the command is still importing (numpy and the extension).
    proc = subprocess.Popen([sys.executable, "-X", "importtime", "-m", "ndtrace", "--version"],
                            cwd=ROOT, stderr=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    # -X importtime prints a line per import: interrupt at the first one of numpy.
    for line in proc.stderr:
        if "numpy" in line:
            proc.send_signal(signal.SIGINT)
            break
    out, err = proc.communicate(timeout=30)
    if proc.returncode == 0:
        pytest.skip("the imports finished before the signal arrived")
    assert proc.returncode == 130, err
    assert "Traceback" not in err and "\nndtrace: interrupted\n" in err, err

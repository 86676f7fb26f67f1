"""No input may crash, hang or flood (issue 52): pictures and turntables under the memory guard,
field and mesh files read header first, broken archives refused, third-party readers wrapped,
Dask addresses checked, output files with the umask's mode. Each test fails without its fix;
the viewer's part is in tests/test_viewer_server.py.
"""

from __future__ import annotations

import io
import os
import subprocess
import sys
import textwrap
import zipfile

import numpy as np
import pytest

import ndtrace
from ndtrace import _ndtrace, surfaces

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENES = os.path.join(ROOT, "scenes")


def run_python(code: str, env: dict | None = None, timeout: float = 240) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True,
                          cwd=ROOT, timeout=timeout, env=dict(os.environ, **(env or {})))


def cli(*args: str, env: dict | None = None, timeout: float = 240) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "ndtrace", *args], capture_output=True, text=True,
                          cwd=ROOT, timeout=timeout, env=dict(os.environ, **(env or {})))


def scene(dim: int, *objects: dict) -> dict:
    """A scene description of ``objects`` with a small camera."""
    up = [[1.0 if i == k + 1 else 0.0 for i in range(dim)] for k in range(dim - 2)]
    return {"dim": dim, "camera": {"position": [0.0] * (dim - 1) + [4.0], "look_at": [0.0] * dim,
                                   "up": up, "fov": 50, "resolution": 8}, "objects": list(objects)}


CAMERA_4D = ('[camera]\nposition = [0, 0, 0, 4]\nlook_at = [0, 0, 0, 0]\nup = [[0, 1, 0, 0], [0, 0, 1, 0]]\n'
             'fov = 50\nresolution = 8\n')
CAMERA_3D = '[camera]\nposition = [0, 0, 4]\nlook_at = [0, 0, 0]\nup = [[0, 1, 0]]\nfov = 50\nresolution = 8\n'


def one_line_error(p: subprocess.CompletedProcess) -> str:
    """The one line of a command's error (exit status 2), with no traceback."""
    assert p.returncode == 2, (p.returncode, p.stderr)
    lines = [line for line in p.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and "Traceback" not in p.stderr, p.stderr
    return lines[0]


def zeros_npz(path, arrays: dict[str, tuple[tuple[int, ...], str]]) -> None:
    """An .npz of zero arrays of any size, streamed through deflate (never held in memory): a
    few MB on disk that inflate to gigabytes."""
    chunk = bytes(1 << 24)
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED, compresslevel=1) as z:
        for name, (shape, dtype) in arrays.items():
            header = io.BytesIO()
            np.lib.format.write_array_header_1_0(header, {"descr": dtype, "fortran_order": False,
                                                          "shape": shape})
            with z.open(name + ".npy", "w", force_zip64=True) as f:
                f.write(header.getvalue())
                left = int(np.prod(shape)) * np.dtype(dtype).itemsize
                while left:
                    n = min(left, len(chunk))
                    f.write(chunk[:n])
                    left -= n


# -- 2. the composite's picture and a turntable's frames under the memory guard ------------------

@pytest.fixture
def limit(monkeypatch):
    """The memory guard capped (NDTRACE_MEMORY_LIMIT is read at every check)."""
    monkeypatch.setenv("NDTRACE_MEMORY_LIMIT", "256M")


def test_a_picture_too_big_is_refused_before_it_is_drawn(limit):
    rgba = np.zeros((8, 8, 8, 4), np.float32)
    with pytest.raises(ValueError) as e:
        ndtrace.composite(rgba, size=(8192, 8192))
    assert str(e.value).startswith("size: a picture of 8192 × 8192 pixels needs about "), e.value
    assert "(128.0 MiB: half of the 256.0 MiB allowed by NDTRACE_MEMORY_LIMIT)" in str(e.value)
    with pytest.raises(ValueError, match=r"^turntable: 3600 frames of 1024 × 1024 pixels needs about .* "
                                         r"NDTRACE_MEMORY_LIMIT"):
        ndtrace.composite(rgba, size=(1024, 1024), turntable=3600)
    # What fits is still drawn, and a turntable's frames come back as one array.
    frames = ndtrace.composite(rgba, size=(16, 12), turntable=3)
    assert frames.shape == (3, 12, 16, 4)


def test_the_command_refuses_a_huge_picture_or_turntable_before_tracing(tmp_path):
    for flags in (["--size", "16384x16384"], ["--turntable", "3600", "--size", "1024x1024"]):
        out = tmp_path / ("x.gif" if "--turntable" in flags else "x.png")
        p = cli(os.path.join(SCENES, "tesseract.toml"), "-o", str(out), *flags,
                env={"NDTRACE_MEMORY_LIMIT": "1G"})
        line = one_line_error(p)
        assert "needs about" in line and "NDTRACE_MEMORY_LIMIT" in line, line
        assert line.startswith("ndtrace: error: " + ("turntable:" if "--turntable" in flags else "size:")), line
        assert not out.exists()


# -- smaller items -------------------------------------------------------------------------------


def test_the_memory_refusal_says_the_half_it_allows(limit):
    with pytest.raises(ValueError, match=r"needs about 1\.0 GiB of memory, more than this process can spare "
                                         r"\(128\.0 MiB: half of the 256\.0 MiB allowed by NDTRACE_MEMORY_LIMIT\)$"):
        _ndtrace.check_memory(float(1 << 30), "x")


def test_generators_and_thickenings_are_checked_by_the_guard(limit):
    with pytest.raises(ValueError, match=r"^samples = 100000: a surface of 10000000000 vertices needs about"):
        surfaces.clifford_torus(100_000)
    with pytest.raises(ValueError, match=r"^thicken_points of 1000000 points × .* needs about .* NDTRACE_MEMORY_LIMIT"):
        ndtrace.mesh.thicken_points(np.zeros((1_000_000, 4)), 0.1, subdivisions=5)
    v, t = surfaces.clifford_torus(400)
    with pytest.raises(ValueError, match=r"^thicken_surface of 160000 vertices and 320000 triangles × "
                                         r"segments = 4096 needs about"):
        ndtrace.mesh.thicken_surface(v, t, 0.01, segments=4096)

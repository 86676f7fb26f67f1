"""No input may crash, hang or flood (issue 52): pictures and turntables under the memory guard,
field and mesh files read header first, broken archives refused, third-party readers wrapped,
Dask addresses checked, output files with the umask's mode. Each test fails without its fix;
the viewer's part is in tests/test_viewer_server.py.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import socket
import stat
import subprocess
import sys
import textwrap
import threading
import time
import zipfile

import numpy as np
import pytest

import ndtrace
from ndtrace import _ndtrace, cluster, mesh, surfaces

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


def test_the_viewer_refuses_a_picture_that_does_not_fit(limit):
    scene = ndtrace.load_file(os.path.join(SCENES, "tesseract.toml"))
    with pytest.raises(ValueError, match=r"^size: a picture of 16000 × 16000 pixels needs about"):
        ndtrace.viewer.ViewSession(scene, size=(16000, 16000))


# -- 3. fields and meshes read header first ----------------------------------------------------

@pytest.fixture(scope="module")
def zeros_640(tmp_path_factory):
    """The issue's reproducer: a 9 MB .npz of 640³ float64 zeros (2 GiB inflated)."""
    path = tmp_path_factory.mktemp("big") / "zeros.npz"
    zeros_npz(path, {"field": ((640, 640, 640), "<f8")})
    return path


def test_a_deflated_field_is_refused_from_its_header_before_it_is_inflated(zeros_640, tmp_path):
    scene = tmp_path / "field.toml"
    scene.write_text(f'dim = 4\n{CAMERA_4D}[[objects]]\nshape = "elevation"\nfield = "{zeros_640}"\n')
    # Under a 3 GiB address-space limit the old reader aborted in the allocator; without one it
    # refused only after a peak of 4 GB. Now: a refusal, and the peak stays far below the array.
    p = run_python(f"""
        import resource, ndtrace
        resource.setrlimit(resource.RLIMIT_AS, (3 << 30, 3 << 30))
        for read in (lambda: ndtrace.load_file({str(scene)!r}), lambda: ndtrace.mesh.read_field({str(zeros_640)!r})):
            try:
                read()
            except ValueError as e:
                print("refused:", e)
        # VmHWM: this process's own peak (ru_maxrss can carry the parent's from before exec).
        hwm = next(line for line in open("/proc/self/status") if line.startswith("VmHWM:"))
        print("peak MiB:", int(hwm.split()[1]) // 1024)
    """, env={"NDTRACE_MEMORY_LIMIT": "1G"})
    assert p.returncode == 0, p.stderr
    lines = p.stdout.splitlines()
    assert len(lines) == 3, p.stdout + p.stderr
    for line in lines[:2]:
        assert str(zeros_640) in line and "shape (640, 640, 640) (<f8) needs about" in line, line
        assert "half of the 1.0 GiB allowed by NDTRACE_MEMORY_LIMIT" in line, line
    assert lines[0].startswith("refused: field.toml: objects[0].field: ") or "objects[0].field" in lines[0]
    assert int(lines[2].split()[-1]) < 600, lines[2]


def test_a_mesh_npz_is_checked_by_the_guard_before_it_is_inflated(tmp_path, limit):
    path = tmp_path / "big.npz"
    zeros_npz(path, {"vertices": ((1 << 23, 4), "<f8"), "simplices": ((4, 4), "<i8")})
    description = scene(4, {"shape": "mesh", "file": str(path)})
    with pytest.raises(ValueError, match=r'objects\[0\]\.file: .*big\.npz: array "vertices": reading an array '
                                         r"of shape \(8388608, 4\) \(<f8\) needs about .* NDTRACE_MEMORY_LIMIT"):
        ndtrace.load_dict(description)
    with pytest.raises(ValueError, match=r'big\.npz: array "vertices": reading an array of shape'):
        mesh.read(path)


# -- 8. an .npz member whose CRC-32 does not match ----------------------------------------------

def test_an_npz_member_with_a_wrong_crc_is_refused(tmp_path):
    v, s = ndtrace.mesh.convex_hull(np.array(np.meshgrid(*[[0.0, 1.0]] * 4)).reshape(4, -1).T)
    good = tmp_path / "good.npz"
    np.savez(good, vertices=v, simplices=s)  # stored, not deflated: the data lie as they are
    data = bytearray(good.read_bytes())
    at = data.index(np.asarray(v, "<f8").tobytes()[:16]) + 8 * 5  # inside vertices' numbers
    data[at] ^= 0x40
    bad = tmp_path / "bad.npz"
    bad.write_bytes(bytes(data))
    ndtrace.load_dict(scene(4, {"shape": "mesh", "file": str(good)}))
    with pytest.raises(ValueError, match=r'objects\[0\]\.file: .*bad\.npz: array "vertices": .*Invalid checksum'):
        ndtrace.load_dict(scene(4, {"shape": "mesh", "file": str(bad)}))
    with pytest.raises(ValueError, match=r"bad\.npz: .*Invalid checksum"):
        mesh.read(bad)


# -- 4, 9. meshio and nibabel wrapped ------------------------------------------------------------

#: The issue's 38-byte PLY: a header that never ends (meshio read empty lines for ever).
PLY_WITHOUT_END = b"ply\nformat ascii 1.0\nelement vertex 3\n"


def test_a_ply_without_end_header_is_an_error_not_a_hang(tmp_path):
    assert len(PLY_WITHOUT_END) == 38
    path = tmp_path / "open.ply"
    path.write_bytes(PLY_WITHOUT_END)
    p = run_python(f"""
        import ndtrace
        try:
            ndtrace.mesh.read({str(path)!r})
        except ValueError as e:
            print(e)
    """, timeout=120)
    assert p.stdout.strip() == f"{path}: not a PLY file meshio can read: no end_header line in its header " \
                               f"(the first {mesh.PLY_HEADER_LIMIT} bytes)", p.stdout + p.stderr
    scene = tmp_path / "ply.toml"
    scene.write_text(f'dim = 3\n{CAMERA_3D}[[objects]]\nshape = "mesh"\nfile = "open.ply"\n')
    line = one_line_error(cli(str(scene), "-o", str(tmp_path / "x.png"), timeout=120))
    assert "objects[0].file" in line and "open.ply" in line and "end_header" in line, line


@pytest.mark.parametrize("name, text", [
    ("loop.off", b"OFF\n# only comments\n\n"),
    ("loop.mdpa", b"Begin Nodes\n 1 0.0 0.0 0.0\n"),
    ("loop.nas", b"BEGIN BULK\nGRID    1       0       0.0     0.0     0.0\n"),
])
def test_other_readers_known_to_loop_are_prechecked(tmp_path, name, text):
    path = tmp_path / name
    path.write_bytes(text)
    p = run_python(f"""
        import ndtrace
        try:
            ndtrace.mesh.read({str(path)!r})
        except ValueError as e:
            print(e)
    """, timeout=120)
    assert p.stdout.startswith(f"{path}: not an") or p.stdout.startswith(f"{path}: not a "), p.stdout + p.stderr


def test_meshio_system_exit_becomes_a_value_error_naming_the_file(tmp_path, capsys):
    # meshio prints a reader's error, then calls sys.exit(1): a SystemExit that a script's
    # `except Exception` does not catch, and through a scene the message was just "1".
    path = tmp_path / "cells.vtk"
    path.write_bytes(b"# vtk DataFile Version 4.2\nx\nASCII\nDATASET POLYDATA\nPOINTS 1 float\n0 0 0\n")
    with pytest.raises(ValueError) as e:
        mesh.read(path)
    assert str(e.value).startswith(f"{path}: meshio cannot read it: ") and str(e.value) != f"{path}: meshio cannot read it: 1"
    assert capsys.readouterr().out == ""
    with pytest.raises(ValueError, match=r"objects\[0\]\.file: .*cells\.vtk: meshio cannot read it"):
        ndtrace.load_dict(scene(3, {"shape": "mesh", "file": str(path)}))


def test_ctrl_c_in_a_mesh_reader_stops_the_load(tmp_path, monkeypatch):
    path = tmp_path / "slow.obj"
    path.write_text("v 0 0 0\n")

    def interrupted(*_args):
        raise KeyboardInterrupt

    monkeypatch.setattr(ndtrace._description, "read", interrupted)
    with pytest.raises(KeyboardInterrupt):
        ndtrace.load_dict(scene(3, {"shape": "mesh", "file": str(path)}))


@pytest.mark.parametrize("name, content", [
    ("truncated.npz", b"PK\x03\x04\x14\x00\x00\x00"),  # zipfile: BadZipFile
    ("empty.npy", b""),  # numpy: EOFError
    ("huge.npy", b"\x93NUMPY\x01\x00v\x00{'descr': '<f8', 'fortran_order': False, 'shape': (4000000000, 4000000000), }"
                 + b" " * 41 + b"\n"),  # numpy: MemoryError / ValueError
])
def test_field_and_mesh_files_raise_value_errors_naming_the_file(tmp_path, name, content):
    path = tmp_path / name
    path.write_bytes(content)
    for read in (mesh.read_field, mesh.read):
        if read is mesh.read and name.endswith(".npy"):
            continue
        with pytest.raises(ValueError) as e:
            read(path)
        assert str(path) in str(e.value) and "\n" not in str(e.value), e.value


# -- 5, 11. --dask addresses ---------------------------------------------------------------------

@contextlib.contextmanager
def listening(answer: bytes | None):
    """A TCP server on 127.0.0.1 that accepts and then says nothing (``answer`` None) or
    answers ``answer`` to whatever it is sent (an HTTP server's reply)."""
    server = socket.create_server(("127.0.0.1", 0))
    server.settimeout(0.2)
    stop = threading.Event()
    conns = []

    def serve():
        while not stop.is_set():
            try:
                conn, _ = server.accept()
            except TimeoutError:
                continue
            conns.append(conn)
            if answer is not None:
                conn.settimeout(5)
                with contextlib.suppress(OSError):
                    conn.recv(65536)
                    conn.sendall(answer)

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    try:
        yield f"tcp://127.0.0.1:{server.getsockname()[1]}"
    finally:
        stop.set()
        thread.join(5)
        for c in conns:
            c.close()
        server.close()


HTTP_400 = b"HTTP/1.1 400 Bad Request\r\nContent-Length: 0\r\nConnection: close\r\n\r\n"


@pytest.mark.parametrize("answer", [None, HTTP_400], ids=["silent", "http"])
def test_dask_at_a_server_that_is_no_scheduler_is_one_line_after_the_timeout(monkeypatch, answer):
    pytest.importorskip("distributed")
    monkeypatch.setattr(cluster, "CONNECT_TIMEOUT", 1.0)
    with listening(answer) as address:
        start = time.monotonic()
        with pytest.raises(ValueError, match=rf"^--dask {address}: cannot reach the Dask scheduler: "
                                             r"no Dask handshake within 1 s \(is it a Dask scheduler\?\)$"):
            with cluster.connect(address):
                pass
        assert time.monotonic() - start < 30  # a hang check, not a timing


def test_dask_at_an_http_server_from_the_command_line(tmp_path):
    pytest.importorskip("distributed")
    with listening(HTTP_400) as address:
        line = one_line_error(cli(os.path.join(SCENES, "cube.toml"), "-o", str(tmp_path / "x.png"),
                                  "--dask", address, timeout=120))
    assert line == f"ndtrace: error: --dask {address}: cannot reach the Dask scheduler: no Dask handshake " \
                   "within 10 s (is it a Dask scheduler?)", line


@pytest.mark.parametrize("address", ["ucx://127.0.0.1:8786", "tls://127.0.0.1:8786", "tcp://127.0.0.1",
                                     "tcp://:8786"])
def test_dask_addresses_the_command_cannot_use_are_refused(tmp_path, address):
    with pytest.raises(ValueError, match=r"expected 'local' or a scheduler address tcp://HOST:PORT"):
        cluster.check_address(address)
    p = cli(os.path.join(SCENES, "cube.toml"), "-o", str(tmp_path / "x.png"), "--dask", address)
    assert p.returncode == 2 and "Traceback" not in p.stderr, p.stderr
    assert "expected 'local' or a scheduler address" in p.stderr.splitlines()[-1]


# -- 12. output files get the umask's mode, or the replaced file's -------------------------------

def picture() -> np.ndarray:
    p = np.zeros((4, 6, 4), np.float32)
    p[..., 3] = 1
    return p


@pytest.fixture
def umask_022():
    old = os.umask(0o022)
    yield
    os.umask(old)


def mode(path) -> int:
    return stat.S_IMODE(os.stat(path).st_mode)


@pytest.mark.parametrize("ext", [".png", ".jpg", ".webp", ".tif", ".exr"])
def test_pictures_get_the_umasks_mode_or_keep_the_replaced_files(tmp_path, umask_022, ext):
    path = tmp_path / f"p{ext}"
    write = ndtrace.write_exr if ext == ".exr" else ndtrace.write_image
    write(path, picture())
    assert mode(path) == 0o644
    os.chmod(path, 0o640)
    write(path, picture())
    assert mode(path) == 0o640
    assert sorted(os.listdir(tmp_path)) == [path.name]


def test_svg_and_animations_get_the_umasks_mode(tmp_path, umask_022):
    scene = ndtrace.load_file(os.path.join(SCENES, "tesseract_spin.toml"))
    svg = tmp_path / "t.svg"
    ndtrace.write_svg(svg, ndtrace.trace(ndtrace.load_dict(dict(scene.to_dict(), animation=None) | {
        "camera": dict(scene.to_dict()["camera"], resolution=12)})), size=(32, 32))
    assert mode(svg) == 0o644
    frames = np.stack([picture()] * 2)
    from ndtrace.animation import write_frames

    gif = tmp_path / "a.gif"
    write_frames(gif, frames, 10.0)
    assert mode(gif) == 0o644
    os.chmod(gif, 0o600)
    write_frames(gif, frames, 10.0)
    assert mode(gif) == 0o600


def test_a_long_legal_output_name_is_written(tmp_path):
    for ext, write in ((".png", ndtrace.write_image), (".exr", ndtrace.write_exr)):
        path = tmp_path / ("p" * (250 - len(ext)) + ext)
        write(path, picture())
        assert path.is_file()


def test_an_output_that_is_a_folder_is_refused_before_any_work(tmp_path):
    folder = tmp_path / "out.png"
    folder.mkdir()
    line = one_line_error(cli(os.path.join(SCENES, "cube.toml"), "-o", str(folder)))
    assert line == f"ndtrace: error: -o {folder}: is a folder, not a file to write", line
    with pytest.raises(IsADirectoryError, match="it is a folder"):
        ndtrace.write_image(folder, picture())
    (tmp_path / "d.exr").mkdir()
    with pytest.raises(OSError, match="it is a folder"):
        ndtrace.write_exr(tmp_path / "d.exr", picture())


# -- smaller items -------------------------------------------------------------------------------

def test_an_elevation_overflow_names_the_height_not_a_transform():
    field = np.full((3, 3, 3), 1e308)
    with pytest.raises(ValueError) as e:
        ndtrace.load_dict(scene(4, {"shape": "elevation", "field": field, "height": 10.0}))
    assert "objects[0].height: height 10 × field[0, 0, 0] = 1e308 overflows float64" in str(e.value), e.value
    assert "transform" not in str(e.value)
    with pytest.raises(ValueError, match=r"^field: height 10 × field\[0, 0, 0\] = 1e308 overflows float64"):
        mesh.elevation_map(field, height=10.0)


def test_the_memory_refusal_says_the_half_it_allows(limit):
    with pytest.raises(ValueError, match=r"needs about 1\.0 GiB of memory, more than this process can spare "
                                         r"\(128\.0 MiB: half of the 256\.0 MiB allowed by NDTRACE_MEMORY_LIMIT\)$"):
        _ndtrace.check_memory(float(1 << 30), "x")


def test_generators_refuse_non_finite_vertices():
    with pytest.raises(ValueError, match=r"^radii: vertex 0 is \[inf"):
        surfaces.clifford_torus(8, radii=(float("inf"), 1.0))
    with pytest.raises(ValueError, match=r"^f, radius: vertex 0 is"):
        with np.errstate(divide="ignore", invalid="ignore"):
            surfaces.complex_graph(lambda z: 1 / z, rings=2, sectors=3)
    with pytest.raises(ValueError, match=r"^extent: vertex \d+ is"):
        surfaces.fermat_patch(extent=1000.0)
    with pytest.raises(ValueError, match=r"^radius: vertex \d+ is"):
        surfaces.riemann_root(2, radius=float("inf"), rings=2, sectors=3)


def test_generators_and_thickenings_are_checked_by_the_guard(limit):
    with pytest.raises(ValueError, match=r"^samples = 100000: a surface of 10000000000 vertices needs about"):
        surfaces.clifford_torus(100_000)
    with pytest.raises(ValueError, match=r"^thicken_points of 1000000 points × .* needs about .* NDTRACE_MEMORY_LIMIT"):
        ndtrace.mesh.thicken_points(np.zeros((1_000_000, 4)), 0.1, subdivisions=5)
    v, t = surfaces.clifford_torus(400)
    with pytest.raises(ValueError, match=r"^thicken_surface of 160000 vertices and 320000 triangles × "
                                         r"segments = 4096 needs about"):
        ndtrace.mesh.thicken_surface(v, t, 0.01, segments=4096)


def test_view_threads_are_capped_like_the_commands(tmp_path):
    proc = subprocess.Popen([sys.executable, "-m", "ndtrace", "view", os.path.join(SCENES, "cube.toml"),
                             "--threads", "100000", "--port", "0", "--no-browser"],
                            cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().startswith("http://127.0.0.1:")
    finally:
        proc.send_signal(2)
        _, err = proc.communicate(timeout=60)
    assert f"ndtrace view: --threads 100000 capped at {4 * (os.cpu_count() or 1)}" in err, err
    assert proc.returncode == 0 and "Traceback" not in err, err


def test_json_of_every_reply_is_strict():
    # (The viewer's replies: tests/test_viewer_server.py; here the helper the server uses.)
    from ndtrace.viewer.server import encode_reply

    assert json.loads(encode_reply({"type": "state", "x": 1.5})) == {"type": "state", "x": 1.5}
    bad = json.loads(encode_reply({"type": "state", "seq": 3, "x": float("nan")}))
    assert bad["type"] == "error" and bad["seq"] == 3 and "not JSON" in bad["message"]

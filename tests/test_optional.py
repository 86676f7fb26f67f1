"""Optional dependencies: every feature that needs one says which package and which extra of
``pyproject.toml`` installs it (``ndtrace._optional.need``), with the exception type its caller
raises for other bad input."""

from __future__ import annotations

import ast
import importlib
import os
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest

import ndtrace
from ndtrace import _optional
from ndtrace.cli import UsageError, run

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "python" / "ndtrace"
CUBE = str(ROOT / "scenes" / "cube.toml")


def extras() -> set[str]:
    with open(ROOT / "pyproject.toml", "rb") as f:
        return set(tomllib.load(f)["project"]["optional-dependencies"])


def hide(monkeypatch, module: str) -> None:
    """Makes ``import module`` fail as if it were not installed."""
    monkeypatch.setitem(sys.modules, module, None)


def test_need_imports_or_names_the_extra(monkeypatch):
    assert _optional.need("numpy", extra="mesh", what="x") is np
    hide(monkeypatch, "numpy")
    with pytest.raises(ImportError) as e:
        _optional.need("numpy", extra="mesh", what="counting", package="NumPy")
    assert str(e.value) == 'counting needs NumPy: pip install "ndtrace[mesh]"'


def test_each_feature_names_its_extra(tmp_path, monkeypatch, capsys):
    hide(monkeypatch, "scipy")
    with pytest.raises(ImportError, match=r'^ndtrace\.mesh\.convex_hull needs scipy: pip install "ndtrace\[mesh\]"$'):
        ndtrace.mesh.convex_hull(np.eye(4)[:, :3])

    (tmp_path / "f.nii").write_bytes(b"")
    hide(monkeypatch, "nibabel")
    with pytest.raises(ImportError, match=r'^reading NIfTI fields needs nibabel: pip install "ndtrace\[nifti\]"$'):
        ndtrace.mesh.read_field(tmp_path / "f.nii")

    hide(monkeypatch, "distributed")
    scene = ndtrace.load_file(CUBE)
    with pytest.raises(ImportError, match=r'^rendering on Dask needs dask\.distributed: pip install "ndtrace\[dask\]"$'):
        ndtrace.trace(scene, client=object())
    with pytest.raises(UsageError, match=r'^--dask: rendering on Dask needs dask\.distributed: pip install "ndtrace\[dask\]"$'):
        run([CUBE, "-o", str(tmp_path / "cube.png"), "--dask"])

    hide(monkeypatch, "imageio_ffmpeg")
    with pytest.raises(ValueError, match=r'^MP4 output needs imageio-ffmpeg: pip install "ndtrace\[video\]"; '
                                         r"write a \.gif or numbered \.png frames instead$"):
        ndtrace.animate(ndtrace.load_file(ROOT / "scenes" / "tesseract_spin.toml"), tmp_path / "spin.mp4")

    hide(monkeypatch, "anywidget")
    monkeypatch.setattr(importlib.import_module("ndtrace.viewer.widget"), "_CLASS", None)
    with pytest.raises(ImportError, match=r'^ndtrace\.widget needs anywidget: pip install "ndtrace\[notebook\]"$'):
        ndtrace.widget(scene)

    hide(monkeypatch, "aiohttp")
    from ndtrace.viewer.cli import main as view

    assert view([CUBE, "--no-browser"]) == 2
    assert capsys.readouterr().err == 'ndtrace view: error: ndtrace view needs aiohttp: pip install "ndtrace[view]"\n'
    assert os.listdir(tmp_path) == ["f.nii"]


def _need_calls() -> list[tuple[str, ast.Call]]:
    calls = []
    for path in sorted(PACKAGE.rglob("*.py")):
        if path.name == "_optional.py":
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Call) and getattr(node.func, "id", None) in ("need", "install"):
                calls.append((str(path.relative_to(PACKAGE)), node))
    return calls


def test_every_extra_named_exists_in_pyproject():
    known = extras()
    calls = _need_calls()
    assert len(calls) >= 8, "the call sites of need() and install() are found"
    for where, call in calls:
        named = [k.value for k in call.keywords if k.arg == "extra"] or call.args[:1]
        assert len(named) == 1 and isinstance(named[0], ast.Constant), (where, ast.unparse(call))
        assert named[0].value in known, (where, ast.unparse(call), sorted(known))


def test_no_other_hand_written_install_messages():
    # Docstrings may say which extra to install; messages come from ndtrace._optional.
    for path in sorted(PACKAGE.rglob("*.py")):
        if path.name == "_optional.py":
            continue
        tree = ast.parse(path.read_text(encoding="utf-8"))
        docstrings = {id(n.body[0].value) for n in ast.walk(tree)
                      if isinstance(n, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef))
                      and n.body and isinstance(n.body[0], ast.Expr)
                      and isinstance(n.body[0].value, ast.Constant)}
        for node in ast.walk(tree):
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docstrings:
                assert "pip install" not in node.value, f"{path.relative_to(PACKAGE)}:{node.lineno}: use ndtrace._optional"

"""The documentation's examples run: README's Python block and the scene-format page's Python
snippets, so that they cannot drift from the code."""

from __future__ import annotations

import os
import re

import numpy as np

import ndtrace

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def blocks(path: str, language: str) -> list[str]:
    with open(os.path.join(ROOT, path), encoding="utf-8") as f:
        return re.findall(rf"```{language}\n(.*?)```", f.read(), flags=re.S)


def test_readme_python_block_runs(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    os.symlink(os.path.join(ROOT, "scenes"), tmp_path / "scenes")
    (code,) = [b for b in blocks("README.md", "python") if "import ndtrace" in b]
    namespace: dict = {}
    exec(compile(code, "README.md", "exec"), namespace)
    assert namespace["retina"].rgba.shape == (64, 64, 64, 4)
    for name in ("tesseract.png", "retina.exr", "spin.gif"):
        assert (tmp_path / name).stat().st_size > 0, name
    assert not (tmp_path / "spin_0001.png").exists()  # a GIF alone, without keep_frames


def small_scene() -> ndtrace.Scene:
    return ndtrace.load_dict({
        "dim": 4,
        "camera": {"position": [0.5, 0.7, 1.0, 4.0], "look_at": [0, 0, 0, 0],
                   "up": [[0, 1, 0, 0], [0, 0, 1, 0]], "fov": 50, "resolution": 6},
        "objects": [{"shape": "hypercube"}],
        "composite": {"size": [16, 16]},
    })


def test_scene_format_python_snippets_run(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    snippets = blocks("docs/scene-format.md", "python")
    assert snippets, "the page has Python examples"
    for code in snippets:
        namespace = {"ndtrace": ndtrace, "np": np, "scene": small_scene()}
        exec(compile(code, "docs/scene-format.md", "exec"), namespace)
    assert (tmp_path / "turn.gif").exists()


def test_scene_format_toml_examples_load():
    full = [b for b in blocks("docs/scene-format.md", "toml") if b.lstrip().startswith("dim")]
    assert full, "the page has complete TOML scenes"
    for text in full:
        ndtrace.load_toml(text)

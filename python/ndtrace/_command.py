"""What the two commands share, ``ndtrace SCENE -o …`` (:mod:`ndtrace.cli`) and ``ndtrace
view SCENE`` (:mod:`ndtrace.viewer.cli`): their one-line usage errors, loading a ``.toml``
scene or a ``.py`` script, ``--set KEY.PATH=VALUE`` overrides, and integer lists such as
``--size WxH``.
"""

from __future__ import annotations

import copy
import os
import runpy
import sys
import tomllib
import traceback

from .scene import Scene, load_dict, load_file

__all__ = ["UsageError", "ScriptError", "load_scene", "run_script", "set_path", "set_key", "apply_sets",
           "ints", "THREADS_PER_CORE", "max_threads", "capped_threads"]

#: ``--threads`` is capped at this many threads per core: more only costs memory and start-up.
THREADS_PER_CORE = 4


def max_threads() -> int:
    """The most worker threads ``--threads`` may ask for."""
    return THREADS_PER_CORE * (os.cpu_count() or 1)


def capped_threads(threads: int | None, prog: str, quiet: bool = False) -> int | None:
    """``--threads``: at least 1 (else a UsageError), at most :func:`max_threads` (more is
    capped, saying so on stderr unless ``quiet``)."""
    if threads is None:
        return None
    if threads < 1:
        raise UsageError(f"--threads: must be at least 1, got {threads}")
    if threads > max_threads():
        if not quiet:
            print(f"{prog}: --threads {threads} capped at {max_threads()} "
                  f"({THREADS_PER_CORE} per core on {os.cpu_count() or 1} cores)", file=sys.stderr)
        return max_threads()
    return threads


class UsageError(Exception):
    """A problem with the command line or the scene: one line, exit status 2."""


def set_path(text: str) -> tuple[list, object]:
    """``KEY.PATH=VALUE`` → (path steps, value parsed as TOML, or the bare text)."""
    key, sep, value = text.partition("=")
    steps = key.strip().split(".")
    if not sep or not all(steps):
        raise UsageError(f"--set {text}: expected KEY.PATH=VALUE, e.g. camera.fov=40")
    try:
        parsed = tomllib.loads(f"v = {value.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        parsed = value.strip()
    return [int(k) if k.isdigit() else k for k in steps], parsed


def set_key(data: dict, text: str) -> None:
    """Applies one ``--set`` to a scene description (missing tables are created)."""
    steps, value = set_path(text)
    node = data
    for i, step in enumerate(steps):
        where = ".".join(map(str, steps[:i])) or "the scene"
        last = i == len(steps) - 1
        if isinstance(node, list):
            if not isinstance(step, int):
                raise UsageError(f"--set {text}: {where} is a list: expected an index, got {step!r}")
            if step >= len(node):
                raise UsageError(f"--set {text}: {where} has {len(node)} entries, no {step}")
        elif isinstance(node, dict):
            step = str(step)
            if not last and not isinstance(node.get(step), (dict, list)):
                node[step] = {}
        else:
            raise UsageError(f"--set {text}: {where} is a value, not a table or list")
        if last:
            node[step] = value
        else:
            node = node[step]


def apply_sets(scene: Scene, sets: list[str], base: str) -> Scene:
    """The scene with every ``--set`` applied, validated; an error names the first override
    that makes the scene invalid."""
    if not sets:
        return scene
    original = scene.to_dict()
    data = copy.deepcopy(original)
    for text in sets:
        set_key(data, text)
    try:
        return load_dict(data, base=base, name="--set " + " --set ".join(sets))
    except ValueError:
        data = copy.deepcopy(original)
        for text in sets:
            set_key(data, text)
            load_dict(data, base=base, name=f"--set {text}")  # raises for the culprit
        raise


def ints(text: str, option: str, sep: str = ",", positive: bool = True) -> list[int]:
    try:
        values = [int(v) for v in text.split(sep)]
    except ValueError:
        raise UsageError(f"{option}: expected integers separated by '{sep}', got {text!r}") from None
    if positive and any(v <= 0 for v in values):
        raise UsageError(f"{option}: values must be positive, got {text!r}")
    return values


def load_scene(path: str) -> Scene:
    if not os.path.exists(path):
        raise UsageError(f"{path}: no such file")
    if path.endswith(".toml"):
        return load_file(path)
    if path.endswith(".py"):
        namespace = run_script(path, lambda: runpy.run_path(path), "running the script")
        make = namespace.get("scene")
        if not callable(make):
            raise UsageError(f"{path}: a scene script must define scene() returning an ndtrace.Scene")
        scene = run_script(path, make, "scene()")
        if not isinstance(scene, Scene):
            raise UsageError(f"{path}: scene() returned {type(scene).__name__}, not an ndtrace.Scene")
        scene.compiled()  # validate now
        return scene
    raise UsageError(f"{path}: unknown scene type: expected a .toml or .py file")


class ScriptError(UsageError):
    """A ``.py`` scene that does not run: one line naming the script, the line and the error."""


def run_script(path: str, call, what: str):
    """``call()``, with an exception of the user's script turned into one line naming the
    script (and its line): a syntax error, an exception or infinite recursion, or
    ``sys.exit`` (a script that exits has produced no scene)."""
    try:
        return call()
    except SyntaxError as e:
        where = f"{e.filename or path}:{e.lineno}" + (f":{e.offset}" if e.offset else "")
        raise ScriptError(f"{where}: syntax error: {e.msg}") from e
    except SystemExit as e:
        raise ScriptError(f"{path}: {what} called sys.exit({e.code!r}) instead of returning a "
                          "scene") from e
    except UsageError:
        raise
    except Exception as e:
        frames = [f for f in traceback.extract_tb(e.__traceback__)
                  if os.path.abspath(f.filename) == os.path.abspath(path)]
        where = f"{path}:{frames[-1].lineno}" if frames else path
        raise ScriptError(f"{where}: {what} raised {type(e).__name__}: {e}") from e

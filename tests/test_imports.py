"""The package's imports, read from its sources with ``ast`` (what import-linter cannot say; the
layers themselves are the contracts of ``[tool.importlinter]`` in pyproject.toml, checked by
``lint-imports`` in ``.ci/lint-python``):

* no module imports a private name (``_x``) of another ndtrace module: what modules share is
  public in a private module (``ndtrace._util``, ``ndtrace._description``, …);
* no module imports names from the package's ``__init__`` (only its submodules);
* ndtrace modules are imported at module level: a function-level import that dodges a cycle
  is a cycle. Functions import only optional or slow-to-import third-party packages
  (:data:`DEFERRED`);
* the imports between ndtrace modules, wherever they are written, form no cycle.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent.parent / "python" / "ndtrace"

#: Modules without a Python source of their own.
EXTENSIONS = {"ndtrace._ndtrace"}

#: What a function may import when it runs: the optional dependencies (imported through
#: ``ndtrace._optional.need`` or after it) and packages imported late for start-up time (Pillow,
#: the browser).
DEFERRED = {"aiohttp", "anywidget", "distributed", "imageio_ffmpeg", "meshio", "nibabel", "scipy",
            "PIL", "webbrowser"}


def sources(root: Path = PACKAGE) -> dict[str, tuple[str, bool]]:
    """Module name → (source, is a package) for every ``.py`` file of the package."""
    out = {}
    for path in sorted(root.rglob("*.py")):
        parts = list(path.relative_to(root.parent).with_suffix("").parts)
        package = parts[-1] == "__init__"
        if package:
            parts.pop()
        out[".".join(parts)] = (path.read_text(encoding="utf-8"), package)
    return out


def imports(name: str, source: str, package: bool, modules: set[str]):
    """Yields (line, target module, imported name or None, at module level) for each import of
    ``name``'s source, relative imports resolved; ``from m import sub`` of a submodule gives
    the submodule and no name."""
    tree = ast.parse(source)
    here = name if package else name.rpartition(".")[0]

    def walk(node: ast.AST, top: bool):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.Import):
                for alias in child.names:
                    yield child.lineno, alias.name, None, top
            elif isinstance(child, ast.ImportFrom):
                if child.level:
                    base = here.split(".")[: len(here.split(".")) - (child.level - 1)]
                    module = ".".join(base + ([child.module] if child.module else []))
                else:
                    module = child.module or ""
                for alias in child.names:
                    if f"{module}.{alias.name}" in modules:
                        yield child.lineno, f"{module}.{alias.name}", None, top
                    else:
                        yield child.lineno, module, alias.name, top
            else:
                inner = top and not isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda, ast.ClassDef))
                yield from walk(child, inner)

    yield from walk(tree, True)


def problems(modules: dict[str, tuple[str, bool]]) -> list[str]:
    """What the module docstring forbids, one line per offence, and the cycles."""
    known = set(modules) | EXTENSIONS
    root = min(known, key=len)
    out = []
    edges: dict[str, set[str]] = {m: set() for m in modules}
    for name, (source, package) in sorted(modules.items()):
        for line, target, imported, top in imports(name, source, package, known):
            where = f"{name}:{line}"
            ours = target == root or target.startswith(root + ".")
            if not ours:
                if not top and target.split(".")[0] not in DEFERRED:
                    out.append(f"{where}: imports {target} in a function (not an optional or deferred package)")
                continue
            if not top:
                out.append(f"{where}: imports {target} in a function")
            if imported is not None and target == root and name != root:
                out.append(f"{where}: imports {imported} from the package's __init__")
            if imported is not None and target != name and imported.startswith("_") \
                    and not (imported.startswith("__") and imported.endswith("__")):
                out.append(f"{where}: imports the private name {imported} of {target}")
            if target in modules and target != name and target != root:
                edges[name].add(target)
    out += [f"import cycle among {', '.join(members)}: {' -> '.join(path)}" for members, path in cycles(edges)]
    return out


def cycles(edges: dict[str, set[str]]) -> list[tuple[list[str], list[str]]]:
    """The modules of each strongly connected component that has a cycle (Tarjan), and one
    cycle through them."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    found = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in sorted(edges[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                component.append(w)
                if w == v:
                    break
            if len(component) > 1 or v in edges[v]:
                found.append((sorted(component), path_within(sorted(component), edges)))

    for v in sorted(edges):
        if v not in index:
            visit(v)
    return found


def path_within(component: list[str], edges: dict[str, set[str]]) -> list[str]:
    """A cycle from the component's first module back to itself, inside the component."""
    start, members = component[0], set(component)
    paths = {start: [start]}
    queue = [start]
    while queue:
        v = queue.pop(0)
        for w in sorted(edges[v] & members):
            if w == start:
                return paths[v] + [start]
            if w not in paths:
                paths[w] = paths[v] + [w]
                queue.append(w)
    raise AssertionError("a strongly connected component without a cycle")


def test_the_package_imports_keep_the_rules():
    modules = sources()
    assert {"ndtrace", "ndtrace.scene", "ndtrace.viewer", "ndtrace.viewer.widget"} <= set(modules)
    assert problems(modules) == []


def test_the_rules_see_each_offence():
    # The checks themselves can fail: a small package that breaks every rule once.
    modules = {
        "pkg": ("from . import low, high\n", True),
        "pkg.low": ("from . import _ext\nfrom .shared import _helper\n\ndef f():\n"
                    "    from .high import g\n    import scipy\n    import json\n", False),
        "pkg.high": ("from . import __version__\nfrom .low import f\n", False),
        "pkg.shared": ("_helper = 1\n", False),
    }
    EXTENSIONS.add("pkg._ext")
    try:
        found = problems(modules)
    finally:
        EXTENSIONS.discard("pkg._ext")
    assert found == [
        "pkg.high:1: imports __version__ from the package's __init__",
        "pkg.low:2: imports the private name _helper of pkg.shared",
        "pkg.low:5: imports pkg.high in a function",
        "pkg.low:7: imports json in a function (not an optional or deferred package)",
        "import cycle among pkg.high, pkg.low: pkg.high -> pkg.low -> pkg.high",
    ]


#: ``dir(ndtrace)`` before the namespace became lazy (issue 50), without the private helpers of
#: ``__init__``: each must still be an attribute.
NAMESPACE = [
    "InternalError", "MAX_DIM", "MIN_DIM", "Retina", "Scene", "__version__", "_ndtrace", "animate",
    "animation", "composite", "display", "edge_segments", "edges", "files", "frames", "geometry",
    "load_dict", "load_file", "load_toml", "mesh", "read_exr", "release_buffers", "retina", "rotation",
    "scene", "show", "surfaces", "svg", "thicken", "trace", "viewer", "visible_edges", "widget",
    "write_exr", "write_image", "write_png", "write_svg",
]

#: The submodules ``import ndtrace`` leaves for their first use.
LAZY_MODULES = ["animation", "edges", "frames", "rotation", "slicing", "surfaces", "svg", "viewer"]


def test_the_lazy_namespace_has_every_name_and_loads_it_on_first_use():
    # A fresh interpreter: this one has imported everything already.
    script = f"""
import sys, ndtrace
lazy = {[f"ndtrace.{m}" for m in LAZY_MODULES]!r}
print(sorted(m for m in lazy if m in sys.modules))
print(sorted(set({NAMESPACE!r}) - set(dir(ndtrace))))
print(sorted(ndtrace.__all__) == sorted(set(ndtrace.__all__)) and set(ndtrace.__all__) <= set(dir(ndtrace)))
values = {{name: getattr(ndtrace, name) for name in {NAMESPACE!r}}}
print(sorted(m for m in lazy if m not in sys.modules))
print(ndtrace.widget is ndtrace.viewer.widget and ndtrace.animate is ndtrace.animation.animate
      and ndtrace.write_svg is ndtrace.svg.write_svg and ndtrace.frames is sys.modules["ndtrace.frames"])
namespace = {{}}
exec("from ndtrace import *", namespace)
print(sorted(set(ndtrace.__all__) - set(namespace)))
try:
    ndtrace.no_such_name
except AttributeError as e:
    print(e)
"""
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                         check=True).stdout.splitlines()
    assert out == ["[]", "[]", "True", "[]", "True", "[]", "module 'ndtrace' has no attribute 'no_such_name'"]


def test_the_lazy_names_are_declared_for_type_checkers():
    # __init__'s `if TYPE_CHECKING:` imports name the same things as its _LAZY table.
    import ndtrace

    tree = ast.parse((PACKAGE / "__init__.py").read_text(encoding="utf-8"))
    (block,) = [n for n in tree.body if isinstance(n, ast.If) and ast.unparse(n.test) == "_typing.TYPE_CHECKING"]
    declared = {}
    for node in block.body:
        if isinstance(node, ast.Assign):  # name = module.attribute
            (target,), value = node.targets, node.value
            assert isinstance(target, ast.Name) and isinstance(value, ast.Attribute), ast.unparse(node)
            declared[target.id] = (ast.unparse(value.value), value.attr)
            continue
        assert isinstance(node, ast.ImportFrom) and node.level == 1, ast.unparse(node)
        for alias in node.names:
            declared[alias.asname or alias.name] = (node.module, alias.name) if node.module else (alias.name, None)
    assert declared == ndtrace._LAZY
    assert sorted(m for m, attribute in ndtrace._LAZY.values() if attribute is None) == LAZY_MODULES

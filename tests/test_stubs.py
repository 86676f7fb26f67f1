"""The hand-written stubs ``python/ndtrace/_ndtrace.pyi`` against the compiled extension: every
public name of the module (functions, classes and their methods and properties, constants, the
kernel submodules ``geometry`` and ``rotation``) is in the stub and every name of the stub is in
the module; a function or method with a ``__text_signature__`` has the stub's parameters (names,
kinds, which have defaults, and the defaults the stub writes out)."""

from __future__ import annotations

import ast
import inspect
from pathlib import Path
from types import ModuleType

from ndtrace import _ndtrace

STUB = Path(__file__).resolve().parent.parent / "python" / "ndtrace" / "_ndtrace.pyi"

#: Annotations checked against the runtime value's type (the others are numpy or typing forms).
SIMPLE_TYPES = {"int": int, "float": float, "str": str, "bool": bool, "tuple": tuple, "list": list,
                "dict": dict}


def public(name: str) -> bool:
    return not name.startswith("_") or name == "__version__"


def members(body: list[ast.stmt]) -> dict[str, ast.stmt]:
    """The public names a stub module or class body declares: functions, classes, annotated
    or assigned names."""
    out: dict[str, ast.stmt] = {}
    for node in body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            names = [node.name]
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            names = [node.target.id]
        elif isinstance(node, ast.Assign):
            names = [t.id for t in node.targets if isinstance(t, ast.Name)]
        else:
            continue
        out.update((n, node) for n in names if public(n))
    return out


STUB_TREE = ast.parse(STUB.read_text(encoding="utf-8"))
STUB_MODULE = members(STUB_TREE.body)
STUB_CLASSES = {n.name: n for n in STUB_TREE.body if isinstance(n, ast.ClassDef)}


def runtime_names(obj) -> set[str]:
    if isinstance(obj, ModuleType):
        return {n for n in dir(obj) if public(n)}
    return {n for n in vars(obj) if public(n)}


def stub_parameters(fn: ast.FunctionDef, drop_self: bool) -> list[tuple[str, str, bool, object]]:
    """(name, kind, has a default, the default if the stub writes a literal, else ...)."""
    a = fn.args
    positional = [(p, "POSITIONAL_ONLY") for p in a.posonlyargs] + [(p, "POSITIONAL_OR_KEYWORD") for p in a.args]
    defaults = [None] * (len(positional) - len(a.defaults)) + list(a.defaults)
    rows = [(p.arg, kind, d) for (p, kind), d in zip(positional, defaults, strict=True)]
    if a.vararg:
        rows.append((a.vararg.arg, "VAR_POSITIONAL", None))
    rows += [(p.arg, "KEYWORD_ONLY", d) for p, d in zip(a.kwonlyargs, a.kw_defaults, strict=True)]
    if a.kwarg:
        rows.append((a.kwarg.arg, "VAR_KEYWORD", None))
    if drop_self:
        assert rows and rows[0][0] == "self", f"{fn.name}: a method's first parameter is self"
        rows = rows[1:]
    out = []
    for name, kind, default in rows:
        value: object = ...
        if default is not None:
            try:
                value = ast.literal_eval(default)
            except ValueError:
                pass
        out.append((name, kind, default is not None, value))
    return out


def runtime_parameters(obj) -> list[tuple[str, str, bool, object]] | None:
    if not getattr(obj, "__text_signature__", None):
        return None
    params = list(inspect.signature(obj).parameters.values())
    if params and params[0].name == "self":
        params = params[1:]
    return [(p.name, p.kind.name, p.default is not p.empty,
             ... if p.default is p.empty else p.default) for p in params]


def same_parameters(where: str, obj, fn: ast.FunctionDef, drop_self: bool) -> list[str]:
    runtime = runtime_parameters(obj)
    if runtime is None:
        return []
    stub = stub_parameters(fn, drop_self)
    written = [(n, k, d) for n, k, d, _ in stub]
    if [(n, k, d) for n, k, d, _ in runtime] != written:
        return [f"{where}: the extension has {obj.__text_signature__}, the stub {ast.unparse(fn.args)}"]
    return [f"{where}({name}=...): default {r!r} in the extension, {s!r} in the stub"
            for (name, _, _, r), (_, _, _, s) in zip(runtime, stub, strict=True)
            if s is not ... and (r is ... or r != s or type(r) is not type(s))]


def compare(where: str, obj, declared: dict[str, ast.stmt], drop_self: bool) -> list[str]:
    """The differences between a module or class and the stub's declarations of it."""
    problems = []
    names = runtime_names(obj)
    problems += [f"{where}.{n}: in the extension, not in the stub" for n in sorted(names - set(declared))]
    problems += [f"{where}.{n}: in the stub, not in the extension" for n in sorted(set(declared) - names)]
    for name in sorted(names & set(declared)):
        value, node = getattr(obj, name), declared[name]
        here = f"{where}.{name}"
        raw = vars(obj).get(name) if isinstance(obj, type) else None
        if isinstance(node, ast.FunctionDef):
            is_property = any(ast.unparse(d) == "property" for d in node.decorator_list)
            if is_property != inspect.isgetsetdescriptor(raw):
                problems.append(f"{here}: a property in {'the stub' if is_property else 'the extension'} only")
            elif not callable(value) and not is_property:
                problems.append(f"{here}: a function in the stub, a {type(value).__name__} in the extension")
            elif not is_property:
                problems += same_parameters(here, value, node, drop_self)
        elif isinstance(node, ast.ClassDef):
            if not isinstance(value, type):
                problems.append(f"{here}: a class in the stub, a {type(value).__name__} in the extension")
            else:
                problems += compare(here, value, members(node.body), drop_self=True)
        else:  # an annotated name: a constant, or a kernel submodule typed by a stub class
            annotation = node.annotation if isinstance(node, ast.AnnAssign) else None
            base = annotation.value if isinstance(annotation, ast.Subscript) else annotation
            kind = base.id if isinstance(base, ast.Name) else None
            if isinstance(value, ModuleType):
                if kind not in STUB_CLASSES:
                    problems.append(f"{here}: a module in the extension, annotated {kind} in the stub")
                else:  # its functions are declared as methods of that class
                    problems += compare(here, value, members(STUB_CLASSES[kind].body), drop_self=True)
            elif kind in SIMPLE_TYPES and not isinstance(value, SIMPLE_TYPES[kind]):
                problems.append(f"{here}: {type(value).__name__} in the extension, {kind} in the stub")
    return problems


def test_the_stub_declares_what_the_extension_defines():
    assert compare("_ndtrace", _ndtrace, STUB_MODULE, drop_self=False) == []


def test_the_extension_exports_its_public_names():
    assert sorted(_ndtrace.__all__) == sorted(runtime_names(_ndtrace))


def test_the_comparison_sees_a_missing_name_and_a_changed_signature():
    # The check itself can fail: a stub without one name, or with one parameter renamed.
    without = {k: v for k, v in STUB_MODULE.items() if k != "release_buffers"}
    assert compare("_ndtrace", _ndtrace, without, drop_self=False) == [
        "_ndtrace.release_buffers: in the extension, not in the stub"]
    renamed = ast.parse("def to_srgb8(rgba, transparent: bool = False): ...").body[0]
    assert compare("_ndtrace", _ndtrace, {**STUB_MODULE, "to_srgb8": renamed}, drop_self=False) == [
        "_ndtrace.to_srgb8: the extension has (rgba, opaque=False), the stub rgba, transparent: bool=False"]
    kernel = STUB_CLASSES["_RotationKernels"]
    assert compare("_ndtrace.rotation", _ndtrace.rotation, {**members(kernel.body), "extra": kernel.body[-1]},
                   drop_self=True) == ["_ndtrace.rotation.extra: in the stub, not in the extension"]


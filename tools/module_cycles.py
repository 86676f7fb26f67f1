#!/usr/bin/env python3
"""Fails when the core crate's modules import each other in a circle.

Reads the `crate::…`, `super::…` and `self::…` paths of the non-test code of
crates/ndtrace/src (comments, doc comments and `#[cfg(test)]` items left out) and checks two
graphs for cycles: the top-level modules (`scene`, `render`, `accel`, …) and, inside each
folder, its files (`scene::build`, `scene::fields`, …). A folder's `mod.rs` declaring and
re-exporting its own files is structure, not a dependency, and is not counted.

    python3 tools/module_cycles.py [--edges | --layers]

`--edges` prints every edge; `--layers` the top-level modules by layer, as docs/architecture.md
lists them (a test checks that the page says the same).
"""
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent / "crates" / "ndtrace" / "src"


def module_of(path: Path) -> tuple[str, ...]:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] in ("mod", "lib"):
        parts.pop()
    return tuple(parts)


def strip_comments(text: str) -> str:
    """The code alone: comments (doc comments too), string and char literals blanked out."""
    out, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            i = text.find("\n", i)
            i = n if i == -1 else i
        elif text.startswith("/*", i):
            depth, i = 1, i + 2
            while i < n and depth:
                if text.startswith("/*", i):
                    depth, i = depth + 1, i + 2
                elif text.startswith("*/", i):
                    depth, i = depth - 1, i + 2
                else:
                    i += 1
        elif m := re.compile(r'r(#*)"').match(text, i) if c == "r" and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")) else None:
            end = text.find('"' + m.group(1), m.end())
            out.append('""')
            i = end + 1 + len(m.group(1))
        elif c == '"':
            i += 1
            while i < n and text[i] != '"':
                i += 2 if text[i] == "\\" else 1
            out.append('""')
            i += 1
        elif c == "'" and (m := re.compile(r"'(?:\\.[^']*|[^\\'])'").match(text, i)):
            out.append("' '")
            i = m.end()
        else:
            out.append(c)
            i += 1
    return "".join(out)


def strip_test_items(text: str) -> str:
    """Removes every item under `#[cfg(test)]` (a `mod x;`, or anything up to its closing brace)."""
    out, i = [], 0
    for m in re.finditer(r"#\[cfg\(test\)\]", text):
        if m.start() < i:
            continue
        out.append(text[i:m.start()])
        j = m.end()
        semi, brace = text.find(";", j), text.find("{", j)
        if brace == -1 or (semi != -1 and semi < brace):
            i = semi + 1
            continue
        depth, k = 0, brace
        while k < len(text):
            depth += {"{": 1, "}": -1}.get(text[k], 0)
            k += 1
            if depth == 0:
                break
        i = k
    out.append(text[i:])
    return "".join(out)


def expand_use_groups(text: str):
    """Yields every path of the source: `use a::{b, c::{d}}` gives a::b and a::c::d."""
    for m in re.finditer(r"\buse\s+([^;]+);", text):
        tree = re.sub(r"\s+as\s+\w+", "", m.group(1))
        yield from _expand(re.sub(r"\s+", "", tree))
    body = re.sub(r"\buse\s+[^;]+;", "", text)
    yield from re.findall(r"(?:\$?crate|super|self)(?:::(?:super|[A-Za-z_][A-Za-z0-9_]*))+", body)


def _expand(tree: str):
    i = tree.find("{")
    if i == -1:
        yield tree
        return
    prefix, inner = tree[:i], tree[i + 1:-1]
    depth, start = 0, 0
    for k, c in enumerate(inner + ","):
        if c == "{":
            depth += 1
        elif c == "}":
            depth -= 1
        elif c == "," and depth == 0:
            part = inner[start:k]
            start = k + 1
            if part:
                yield from _expand(prefix + part)


def resolve(path: str, here: tuple, modules: set, reexports: dict) -> tuple | None:
    """The module a path names: its longest prefix that is a module of the crate, or, for an item
    a folder re-exports from one of its files (`crate::NdError`, `crate::accel::Bvh`), that
    file's module."""
    segs = path.split("::")
    if segs[0] in ("crate", "$crate"):
        target, rest = (), segs[1:]
    elif segs[0] in ("super", "self"):
        target, rest = here, segs
        while rest and rest[0] in ("super", "self"):
            target = target[:-1] if rest[0] == "super" else target
            rest = rest[1:]
    else:
        return None
    for s in rest:
        if target + (s,) in modules:
            target = target + (s,)
        elif s in reexports.get(target, {}):
            return reexports[target][s]
        else:
            break
    return target


def circles(graph: dict) -> list:
    """The strongly connected components of more than one module (Tarjan), each sorted."""
    index, low, on, stack, out = {}, {}, set(), [], []
    nodes = sorted(set(graph) | {w for ws in graph.values() for w in ws})

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in nodes:
        if v not in index:
            visit(v)
    return out


def layers(graph: dict, nodes: set) -> list:
    """The modules by layer: a module's layer is one more than the highest layer it uses (1 for
    one that uses no other module)."""
    depth: dict = {}

    def of(v):
        if v not in depth:
            depth[v] = 1 + max((of(w) for w in graph.get(v, ())), default=0)
        return depth[v]

    out: dict = {}
    for v in nodes:
        out.setdefault(of(v), []).append(v)
    return [sorted(out[k]) for k in sorted(out)]


def shipped_files() -> dict:
    """The files of the shipped code: those `mod` declarations outside `#[cfg(test)]` reach from
    lib.rs, with their code (test items removed)."""
    found, todo = {}, [ROOT / "lib.rs"]
    while todo:
        f = todo.pop()
        code = strip_test_items(strip_comments(f.read_text()))
        found[f] = code
        folder = f.parent if f.name in ("mod.rs", "lib.rs") else f.parent / f.stem
        for name in re.findall(r"^\s*(?:pub(?:\([a-z]+\))?\s+)?mod\s+([a-z_0-9]+)\s*;", code, re.M):
            for child in (folder / f"{name}.rs", folder / name / "mod.rs"):
                if child.exists():
                    todo.append(child)
                    break
            else:
                sys.exit(f"module_cycles: {f}: no file for `mod {name};`")
    return found


def main() -> int:
    files = shipped_files()
    modules = {module_of(f) for f in files}
    # What each folder (and the crate's root) re-exports from its own files: `pub use
    # error::NdError` in lib.rs, `pub use tree::Bvh` in accel/mod.rs.
    reexports: dict = {}
    for f, code in files.items():
        if f.name not in ("mod.rs", "lib.rs"):
            continue
        here = module_of(f)
        for m in re.finditer(r"\bpub(?:\([a-z]+\))?\s+use\s+([^;]+);", code):
            tree = re.sub(r"\s+as\s+", "@", m.group(1))
            for p in _expand(re.sub(r"\s+", "", tree)):
                segs = p.split("::")
                segs = segs[1:] if segs[0] == "self" else segs
                if len(segs) >= 2 and here + (segs[0],) in modules:
                    name = segs[-1].split("@")[-1]
                    reexports.setdefault(here, {})[name] = here + (segs[0],)
    edges: dict = {}
    for f, code in files.items():
        here = module_of(f)
        is_mod = f.name in ("mod.rs", "lib.rs")
        for p in expand_use_groups(code):
            t = resolve(p, here, modules, reexports)
            if t is None or t == here or not t:
                continue
            if is_mod and t[: len(here)] == here:
                continue  # a folder's mod.rs declaring and re-exporting its own files
            edges.setdefault(here, set()).add(t)
    if "--edges" in sys.argv:
        for a in sorted(edges):
            for b in sorted(edges[a]):
                print("::".join(a), "->", "::".join(b))
    graphs = {"the top-level modules": {}}
    for a, bs in edges.items():
        for b in bs:
            if a[0] != b[0]:
                graphs["the top-level modules"].setdefault(a[0], set()).add(b[0])
            if len(a) > 1 and a[:-1] == b[:-1]:
                graphs.setdefault(f"the files of {'/'.join(a[:-1])}/", {}).setdefault(a[-1], set()).add(b[-1])
    failed = False
    for where, graph in graphs.items():
        for comp in circles(graph):
            failed = True
            inner = [f"{a} -> {b}" for a in comp for b in sorted(graph.get(a, ())) if b in comp]
            print(f"module_cycles: a cycle among {where}: {', '.join(comp)} ({'; '.join(inner)})")
    if not failed and "--layers" in sys.argv:
        for k, names in enumerate(layers(graphs["the top-level modules"], {m[0] for m in modules if m}), 1):
            print(f"{k}. {', '.join(names)}")
        for folder in sorted({m[:-1] for m in modules if len(m) > 1}):
            files = {m[-1] for m in modules if len(m) > 1 and m[:-1] == folder}
            graph = graphs.get(f"the files of {'/'.join(folder)}/", {})
            steps = ["; ".join(", ".join(n) for n in [names]) for names in layers(graph, files)]
            print(f"{'/'.join(folder)}/: {' ← '.join(steps)}")
        return 0
    if not failed:
        print(f"module_cycles: no cycles ({len(modules)} modules, {sum(map(len, edges.values()))} edges)")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())

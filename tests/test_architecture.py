"""docs/architecture.md against the code: every module of the core, the bindings and the Python
package is named on the page, the page names no module that does not exist, and the layers it
lists are the ones tools/module_cycles.py finds (which also fails on any cycle)."""

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PAGE = ROOT / "docs" / "architecture.md"
CORE = ROOT / "crates" / "ndtrace" / "src"
BINDINGS = ROOT / "crates" / "ndtrace-py" / "src"
PACKAGE = ROOT / "python" / "ndtrace"


def section(title_start: str) -> str:
    """The text of the page's `## ` section whose title starts with `title_start`."""
    text = PAGE.read_text()
    parts = re.split(r"^## ", text, flags=re.M)
    found = [p for p in parts if p.startswith(title_start)]
    assert len(found) == 1, f"docs/architecture.md has no single section '## {title_start}…'"
    return found[0]


def named(text: str, suffix: str) -> set[str]:
    """The files a section's tables name: a row's first cell names a file (`x.rs`) or a folder
    (`x/`), and a folder row's backticked names ending in `suffix` are files of that folder."""
    names = set()
    for row in re.findall(r"^\|(.+)\|\s*$", text, flags=re.M):
        cells = [c.strip() for c in row.split("|")]
        if not cells or set(cells[0]) <= {"-", " "} or cells[0] in ("Module", "File"):
            continue
        keys = re.findall(r"`([^`]+)`", cells[0])
        for key in keys:
            if key.endswith("/"):
                for name in re.findall(r"`([\w/]+" + re.escape(suffix) + r")`", row):
                    names.add(key + name)
            else:
                names.add(key)
    return names


def files(root: Path, suffix: str, skip=()) -> set[str]:
    out = set()
    for f in root.rglob("*" + suffix):
        rel = f.relative_to(root).as_posix()
        if f.name == "tests.rs" or any(rel.startswith(s) for s in skip) or "__pycache__" in rel:
            continue
        out.add(rel)
    return out


@pytest.mark.parametrize("title, root, suffix, skip", [
    ("The core crate", CORE, ".rs", ()),
    ("The bindings", BINDINGS, ".rs", ()),
    ("The Python package", PACKAGE, ".py", ()),
])
def test_the_page_names_every_module_and_no_other(title, root, suffix, skip):
    page = named(section(title), suffix)
    code = files(root, suffix, skip)
    missing = sorted(code - page)
    extra = sorted(n for n in page - code if n.endswith(suffix))
    assert not missing, f"docs/architecture.md ({title}) does not name: {', '.join(missing)}"
    assert not extra, f"docs/architecture.md ({title}) names files that do not exist: {', '.join(extra)}"


def between(text: str, tag: str) -> list[str]:
    m = re.search(rf"<!-- {tag}: begin -->\n(.*?)<!-- {tag}: end -->", text, flags=re.S)
    assert m, f"docs/architecture.md has no <!-- {tag}: begin/end --> block"
    return [line.removeprefix("- ") for line in m.group(1).strip().splitlines()]


def test_the_layers_on_the_page_are_the_code_s():
    out = subprocess.run([sys.executable, str(ROOT / "tools" / "module_cycles.py"), "--layers"],
                         capture_output=True, text=True, check=False)
    assert out.returncode == 0, out.stdout + out.stderr
    lines = out.stdout.strip().splitlines()
    layers = [line for line in lines if re.match(r"\d+\. ", line)]
    folders = [line for line in lines if not re.match(r"\d+\. ", line)]
    text = section("The core crate")
    assert between(text, "layers") == layers, "the layers on the page differ from the code's:\n" + out.stdout
    assert between(text, "folders") == folders, "the folders' orders differ from the code's:\n" + out.stdout


def test_the_cycle_check_fails_on_a_cycle(tmp_path):
    """The checker finds a cycle when one is added (a copy of the crate with one more edge)."""
    import shutil
    src = tmp_path / "crates" / "ndtrace" / "src"
    shutil.copytree(CORE, src)
    (tmp_path / "tools").mkdir()
    shutil.copy(ROOT / "tools" / "module_cycles.py", tmp_path / "tools")
    linalg = src / "linalg.rs"
    linalg.write_text(linalg.read_text() + "\n#[allow(unused)]\nuse crate::scene::Scene;\n")
    out = subprocess.run([sys.executable, str(tmp_path / "tools" / "module_cycles.py")],
                         capture_output=True, text=True, check=False)
    assert out.returncode == 1 and "linalg" in out.stdout and "scene" in out.stdout, out.stdout
    # A test module's imports are not edges of the shipped code.
    linalg.write_text(linalg.read_text().replace("use crate::scene::Scene;", "") +
                      "\n#[cfg(test)]\nmod extra {\n    use crate::scene::Scene;\n}\n")
    out = subprocess.run([sys.executable, str(tmp_path / "tools" / "module_cycles.py")],
                         capture_output=True, text=True, check=False)
    assert out.returncode == 0, out.stdout

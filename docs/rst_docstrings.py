"""A griffe extension for the API reference: ndtrace's docstrings are written in
reStructuredText habits (``code``, :func:`name` roles, ``::`` literal blocks), the site in
Markdown. Roles become code spans and literal blocks fenced code, before the docstrings are
rendered; ``code`` is already a Markdown code span."""

from __future__ import annotations

import re
import textwrap

import griffe

ROLE = re.compile(r":(?:func|class|data|meth|mod|attr|exc|obj):`~?([^`]+)`")


def markdown(text: str) -> str:
    text = ROLE.sub(r"`\1`", text)
    lines = text.split("\n")
    out: list[str] = []
    i = 0
    while i < len(lines):
        line = lines[i]
        if line.rstrip().endswith("::") and not line.strip().startswith(".."):
            # "text::" → "text:"; a bare "::" line disappears; the indented block after it is code.
            head = line.rstrip()[:-1]
            if head.strip() not in ("", ":"):
                out.append(head)
            indent = len(line) - len(line.lstrip())
            j = i + 1
            block: list[str] = []
            while j < len(lines) and (not lines[j].strip() or len(lines[j]) - len(lines[j].lstrip()) > indent):
                block.append(lines[j])
                j += 1
            while block and not block[-1].strip():
                block.pop()
            pad = " " * indent
            out += ["", pad + "```python", *(pad + b for b in textwrap.dedent("\n".join(block)).strip("\n").split("\n")), pad + "```", ""]
            i = j
            continue
        out.append(line)
        i += 1
    return "\n".join(out)


class RstDocstrings(griffe.Extension):
    """Rewrites every docstring from reStructuredText habits to Markdown."""

    def on_instance(self, *, obj: griffe.Object, **kwargs) -> None:  # noqa: ARG002
        if obj.docstring is not None:
            obj.docstring.value = markdown(obj.docstring.value)

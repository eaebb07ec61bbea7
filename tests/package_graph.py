"""The package's modules and their imports, as the layout tests read them
(:mod:`test_layout`, and the API tests' check of the use-case registry)."""

from __future__ import annotations

import ast
from pathlib import Path

from conftest import ROOT

# the folders of the repository that are parts of the htn package
PACKAGE_DIRS = (
    "",
    "api",
    "cli",
    "process",
    "jshop",
    "executor",
    "robot",
    "transform",
    "evaluation",
    "view",
    "up",
    "ros",
    "domains",
    "problems",
)


def package_modules() -> dict[str, Path]:
    """htn's module names -> their files (the package's folders, recursively).

    Only the package's folders are walked: a wheel being built in ``build/``
    by another test worker appears and vanishes while we look."""
    mods = {}
    paths = [*ROOT.glob("*.py")]
    for folder in PACKAGE_DIRS[1:]:
        paths += (ROOT / folder).rglob("*.py")
    for path in sorted(paths):
        rel = path.relative_to(ROOT)
        if any(p.startswith(".") for p in rel.parts):
            continue
        parts = list(rel.with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        mods[".".join(["htn", *parts])] = path
    return mods


def imports_of(name: str, path: Path, modules: dict) -> set[str]:
    """The htn modules that ``name`` imports anywhere in its file (function
    bodies included: a lazy import is still a dependency)."""
    package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                up = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                base = ".".join(up + ([node.module] if node.module else []))
            for a in node.names:
                sub = f"{base}.{a.name}"
                found.add(sub if sub in modules else base)
    return {m for m in found if m in modules and m != name}


def cycles(graph: dict[str, set]) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        work = [(v, iter(sorted(graph[v])))]
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        while work:
            node, it = work[-1]
            for w in it:
                if w not in index:
                    index[w] = low[w] = counter[0]
                    counter[0] += 1
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(sorted(graph[w]))))
                    break
                if w in on:
                    low[node] = min(low[node], index[w])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[node])
                if low[node] == index[node]:
                    comp = []
                    while True:
                        w = stack.pop()
                        on.discard(w)
                        comp.append(w)
                        if w == node:
                            break
                    if len(comp) > 1:
                        out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out

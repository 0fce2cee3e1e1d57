"""The layer picture of the README holds: imports flow one way and there is no cycle.

physics  <-  hyperloop_env (config, stages, envs, STS, verification)
         <-  agents.controllers  <-  agents.evaluation  <-  agents.training

Every import counts, also the ones inside functions (a lazy import is still a dependency).
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("hyperloop_env", "agents")


def _module_name(path: Path) -> str:
    rel = path.relative_to(ROOT).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _modules() -> dict[str, Path]:
    out = {}
    for pkg in PACKAGES:
        for p in (ROOT / pkg).rglob("*.py"):
            out[_module_name(p)] = p
    return out


def _imports(path: Path, name: str, known: set[str]) -> set[str]:
    """Project modules imported by the module at ``path`` (resolved to the longest known
    module name: ``from a.b import c`` is ``a.b.c`` if that is a module, else ``a.b``)."""
    tree = ast.parse(path.read_text())
    is_pkg = path.name == "__init__.py"
    targets: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            targets.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = name.split(".") if is_pkg else name.split(".")[:-1]
                base = base[: len(base) - (node.level - 1)]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            for a in node.names:
                targets.add(f"{mod}.{a.name}")
                targets.add(mod)
    out = set()
    for t in targets:
        parts = t.split(".")
        for k in range(len(parts), 0, -1):
            cand = ".".join(parts[:k])
            if cand in known:
                if cand != name:
                    out.add(cand)
                break
    return out


def _graph() -> dict[str, set[str]]:
    mods = _modules()
    known = set(mods)
    return {m: _imports(p, m, known) for m, p in mods.items()}


def _code_lines(path: Path) -> list[tuple[int, str]]:
    """(line number, code) with strings, docstrings and comments blanked out."""
    import io
    import tokenize

    src = path.read_text()
    lines = src.splitlines()
    out = [list(ln) for ln in lines]
    for tok in tokenize.generate_tokens(io.StringIO(src).readline):
        if tok.type in (tokenize.STRING, tokenize.COMMENT):
            (r0, c0), (r1, c1) = tok.start, tok.end
            for r in range(r0, r1 + 1):
                a = c0 if r == r0 else 0
                b = c1 if r == r1 else len(lines[r - 1])
                out[r - 1][a:b] = " " * (b - a)
    return [(k + 1, "".join(ch)) for k, ch in enumerate(out)]


def _external_imports(path: Path) -> set[str]:
    tree = ast.parse(path.read_text())
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out.update(a.name.split(".")[0] for a in node.names)
        elif isinstance(node, ast.ImportFrom) and not node.level and node.module:
            out.add(node.module.split(".")[0])
    return out


def _cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """A cycle of modules, ignoring the edge from a package's __init__ to its own
    submodules (a package re-exporting what it contains is not a dependency loop)."""
    state: dict[str, int] = {}
    stack: list[str] = []

    def edges(m: str) -> set[str]:
        return {t for t in graph[m] if not t.startswith(m + ".")}

    def visit(m: str) -> list[str] | None:
        state[m] = 1
        stack.append(m)
        for t in sorted(edges(m)):
            if state.get(t) == 1:
                return stack[stack.index(t) :] + [t]
            if t not in state:
                found = visit(t)
                if found:
                    return found
        stack.pop()
        state[m] = 2
        return None

    for m in sorted(graph):
        if m not in state:
            found = visit(m)
            if found:
                return found
    return None


def test_no_import_cycle() -> None:
    assert _cycle(_graph()) is None, " -> ".join(_cycle(_graph()) or [])


def test_cycle_detector_finds_a_cycle() -> None:
    assert _cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert _cycle({"a": {"a.x"}, "a.x": {"b"}, "b": set()}) is None


LAYERS: list[tuple[str, tuple[str, ...]]] = [
    # (modules matching this prefix, may not import these prefixes)
    ("hyperloop_env.physics", ("hyperloop_env.", "agents")),
    ("hyperloop_env", ("agents",)),
    (
        "agents.controllers",
        ("agents.evaluation", "agents.training", "hyperloop_env.physics.layout"),
    ),
    ("agents.evaluation", ("agents.training",)),
]


def test_imports_flow_one_way() -> None:
    graph = _graph()
    bad = []
    for m, targets in graph.items():
        for prefix, forbidden in LAYERS:
            if m == prefix or m.startswith(prefix + "."):
                for t in targets:
                    own = t == prefix or t.startswith(prefix + ".")
                    if any(t == f.rstrip(".") or t.startswith(f) for f in forbidden) and not own:
                        bad.append(f"{m} imports {t}")
                break
    assert not bad, "\n".join(bad)


def test_physics_needs_no_gymnasium() -> None:
    for p in (ROOT / "hyperloop_env" / "physics").rglob("*.py"):
        assert "gymnasium" not in _external_imports(p), p


def test_no_literal_unit_count_outside_the_units_module() -> None:
    """ "Four units" is defined once (physics/units.py): no ``range(4)``, ``(4,)`` or
    ``np.zeros(4)``-style literals in the package code."""
    pattern = re.compile(r"range\(4\)|\(4,\)|zeros\(4\)|ones\(4\)|eye\(4\)|\[0\.0\] \* 4|\(4, ")
    hits = []
    for pkg in PACKAGES:
        for p in (ROOT / pkg).rglob("*.py"):
            for k, code in _code_lines(p):
                if pattern.search(code):
                    hits.append(f"{p.relative_to(ROOT)}:{k}: {code.strip()}")
    assert not hits, "\n".join(hits)


def test_shared_constants_are_defined_once() -> None:
    """PAPER_SCENARIOS, UNIT_NAMES, ENV_ID and the 8 mm clearance have one definition."""
    defs = {"PAPER_SCENARIOS": [], "UNIT_NAMES": [], "ENV_ID": [], "0.008": []}
    files = [p for pkg in (*PACKAGES, "scripts", "speed") for p in (ROOT / pkg).rglob("*.py")]
    for p in [*files, ROOT / "tests" / "golden_cases.py"]:  # the golden tooling too
        for _, code in _code_lines(p):
            for name in ("PAPER_SCENARIOS", "UNIT_NAMES", "ENV_ID"):
                if re.match(rf"^{name}\s*(:[^=]*)?=", code):
                    defs[name].append(str(p.relative_to(ROOT)))
            if re.search(r"(?<![\d.])0\.008(?!\d)", code):
                defs["0.008"].append(str(p.relative_to(ROOT)))
    assert defs["PAPER_SCENARIOS"] == ["hyperloop_env/scenarios.py"]
    assert defs["UNIT_NAMES"] == ["hyperloop_env/physics/units.py"]
    assert defs["ENV_ID"] == ["hyperloop_env/__init__.py"]
    assert defs["0.008"] == ["hyperloop_env/physics/params.py"], defs["0.008"]

"""The leaderboard: the published entrants plus the controllers users scored
(``hyperloop score``), one line each, comparable by construction.

A board is a folder of score results (``score.json`` files written by ``hyperloop score``;
in a checkout ``docs/leaderboard/``). :func:`add` admits one only if it was scored on the
published benchmark (same :data:`~agents.evaluation.published.BENCHMARK_VERSION` and the
same fingerprint digest): a result of another fingerprint is refused
(:class:`LeaderboardError` naming the file and the difference). :func:`table` orders
everyone by the geometric mean of the median roughness capacity θ over the four paper
conditions (the family every score covers, ``--quick`` included). The order is of point
estimates: whether two neighbours differ is what the paired verdicts of a score (and of
the published headline) decide. :func:`readme_block` is the same table under a one-line
caption, the README's leaderboard summary.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from typing import Any

from agents.evaluation.outputs import atomic_write_text
from agents.evaluation.published import BENCHMARK_VERSION, load_published

FAMILY = "roughness"


class LeaderboardError(ValueError):
    """A score result that cannot join the board (the message names the file and why)."""


def _read(path: Path) -> dict[str, Any]:
    try:
        doc = json.loads(path.read_text())
    except FileNotFoundError:
        raise LeaderboardError(f"{path}: not found") from None
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise LeaderboardError(f"{path}: not a readable score result ({exc})") from None
    if not isinstance(doc, dict) or not isinstance(doc.get("leaderboard"), dict):
        raise LeaderboardError(f"{path}: not a score result (no 'leaderboard' entry)")
    return doc


def check(path: Path, published: dict[str, Any]) -> dict[str, Any]:
    """The score result at ``path`` if it may join the board (module docstring)."""
    doc = _read(path)
    e = doc["leaderboard"]
    if e.get("benchmark") != BENCHMARK_VERSION:
        raise LeaderboardError(
            f"{path}: scored on {e.get('benchmark')!r}, the board is {BENCHMARK_VERSION!r}"
        )
    want = published["fingerprint"]["digest"]
    if e.get("fingerprint") != want:
        raise LeaderboardError(
            f"{path}: fingerprint {e.get('fingerprint')!r} is not the published {want!r} "
            "(scored with another model, condition, disturbance, search or seeds)"
        )
    if not isinstance(e.get("controller"), str) or not isinstance(e.get("theta"), dict):
        raise LeaderboardError(f"{path}: the entry has no controller name or θ")
    return doc


def add(
    path: str | Path, board: str | Path, *, overwrite: bool = False, published: Any = None
) -> Path:
    """Admit the score result ``path`` to the board folder ``board`` (refused if another
    fingerprint, or if the controller is on the board already unless ``overwrite``)."""
    pub = published if published is not None else load_published()
    doc = check(Path(path), pub)
    name = doc["leaderboard"]["controller"]
    if name in pub["settings"]["entrants"]:
        raise LeaderboardError(f"{path}: {name!r} is a published entrant's name; rename yours")
    target = Path(board) / f"{re.sub(r'[^A-Za-z0-9_.+-]', '_', name)}.json"
    if target.exists() and not overwrite:
        raise LeaderboardError(f"{target}: {name!r} is on the board already (--overwrite)")
    atomic_write_text(target, json.dumps(doc, indent=1) + "\n")
    return target


def entries(board: str | Path, published: dict[str, Any]) -> list[dict[str, Any]]:
    """The board's rows: every published entrant, then every admitted score result."""
    st = published["settings"]
    rows = []
    for lab in st["entrants"]:
        theta = {
            c: published["cells"][c][FAMILY][lab].get("theta")
            or published["cells"][c][FAMILY][lab].get("median_empirical")
            for c in st["conditions"]
        }
        rows.append({"controller": lab, "theta": theta, "source": "published"})
    folder = Path(board)
    for f in sorted(folder.glob("*.json")) if folder.is_dir() else []:
        e = check(f, published)["leaderboard"]
        theta = {c: e["theta"].get(f"{c}/{FAMILY}") for c in st["conditions"]}
        rows.append(
            {"controller": e["controller"], "theta": theta,
             "source": "score (quick)" if e.get("quick") else "score"}
        )  # fmt: skip
    return rows


def _gmean(vals: list[Any]) -> float:
    ok = [v for v in vals if isinstance(v, int | float) and v > 0]
    return math.exp(sum(map(math.log, ok)) / len(ok)) if len(ok) == len(vals) else math.nan


def _rank_key(g: float) -> float:
    """Highest geometric mean first; an entry without every θ last."""
    return math.inf if math.isnan(g) else -g


def table(board: str | Path, published: dict[str, Any] | None = None) -> str:
    """The leaderboard as Markdown (module docstring)."""
    pub = published if published is not None else load_published()
    conds = pub["settings"]["conditions"]
    rows = entries(board, pub)
    rows.sort(key=lambda r: _rank_key(_gmean(list(r["theta"].values()))))
    head = ["rank", "controller", *(f"θ {c.removeprefix('paper-')}" for c in conds)]
    lines = ["| " + " | ".join([*head, "geometric mean", "source"]) + " |"]
    lines.append("|---:|---|" + "---:|" * (len(conds) + 1) + "---|")
    for i, r in enumerate(rows, 1):
        cells = [f"{r['theta'][c]:.3g}" if r["theta"][c] else "n/a" for c in conds]
        g = _gmean(list(r["theta"].values()))
        gm = "n/a" if math.isnan(g) else f"{g:.3g}"
        lines.append(
            f"| {i} | `{r['controller']}` | " + " | ".join(cells) + f" | {gm} | {r['source']} |"
        )
    return "\n".join(lines) + "\n"


README_ROWS = 15
"""The README shows the board's first rows; the docs page shows all of it."""
START, END = "<!-- leaderboard:start -->", "<!-- leaderboard:end -->"


def readme_block(board: str | Path, published: dict[str, Any] | None = None) -> str:
    """The README's leaderboard summary: the first :data:`README_ROWS` rows of
    :func:`table` under a one-line caption naming the benchmark, its fingerprint and how
    many entrants the board holds (the README keeps it between ``<!-- leaderboard:start
    -->`` and ``<!-- leaderboard:end -->``; :func:`update_readme` rewrites it)."""
    pub = published if published is not None else load_published()
    n_pub = len(pub["settings"]["entrants"])
    n_all = len(entries(board, pub))
    n_scored = n_all - n_pub
    scored = f"{n_scored} scored controller" + ("" if n_scored == 1 else "s")
    caption = (
        f"Median {FAMILY} capacity θ per paper condition and its geometric mean: "
        f"{n_pub} published entrants and {scored} (benchmark `{BENCHMARK_VERSION}`, "
        f"fingerprint `{pub['fingerprint']['digest']}`; `hyperloop leaderboard show`):"
    )
    lines = table(board, pub).splitlines()
    shown = "\n".join(lines[: 2 + README_ROWS]) + "\n"
    more = n_all - README_ROWS
    tail = f"\n… and {more} more: the full board is in docs/leaderboard.md.\n" if more > 0 else ""
    return f"{caption}\n\n{shown}{tail}"


def update_readme(readme: str | Path, board: str | Path) -> bool:
    """Rewrite the leaderboard block of ``readme`` from ``board``; False (nothing written)
    if the file has no such block."""
    p = Path(readme)
    text = p.read_text() if p.is_file() else ""
    if text.count(START) != 1 or text.count(END) != 1:
        return False
    head, rest = text.split(START, 1)
    atomic_write_text(p, head + START + "\n" + readme_block(board) + END + rest.split(END, 1)[1])
    return True

"""The README's Table 1 snippet, run exactly as printed: the core chooses Agent2 (paper §2.1)."""

from __future__ import annotations

import contextlib
import io
import re
from pathlib import Path

README = Path(__file__).resolve().parents[2] / "README.md"


def _table1_snippet() -> str:
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(encoding="utf-8"), flags=re.S)
    matches = [b for b in blocks if "table1" in b]
    assert len(matches) == 1, "the README must hold exactly one Table 1 snippet"
    return matches[0]


def test_readme_table1_snippet_chooses_agent2_with_the_tables_totals():
    code = _table1_snippet()
    out = io.StringIO()
    namespace: dict = {}
    with contextlib.redirect_stdout(out):
        exec(compile(code, str(README), "exec"), namespace)
    printed = out.getvalue().strip()
    claimed = code.strip().splitlines()[-1].split("#", 1)[1].strip()  # what the README says it prints
    assert printed == claimed == "Agent2 [0.45, 0.7, 0.6, 0.45]"
    cycle = namespace["result"].trace[0]
    assert cycle.stage_cycle == 0  # decided at the stage's first cycle
    assert [r.opportunistic for r in cycle.ratings] == [0.0, 0.8, 0.2, 0.5]

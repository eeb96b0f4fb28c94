"""The table of the grasp planner's board entries (type, meaning, writers, readers), generated
from the declarations into ``docs/planner.md`` (a test fails when it no longer matches)::

    python -m eos_svc.agents.board_table [docs/planner.md]   # print it, or rewrite it there
"""

from __future__ import annotations

import sys
from collections.abc import Iterable, Mapping
from pathlib import Path

from eos_svc.agent import Agent
from eos_svc.board_access import access_map
from eos_svc.errors import ValidationError
from eos_svc.schema.board_entries import AFTER_RUN, ENTRIES, OUTSIDE_WRITERS, Entry, type_name


def access_table(agents: Iterable[Agent], entries: Mapping[str, Entry] = ENTRIES) -> str:
    """A Markdown table of every entry: its type, meaning, who writes and who reads it (from the
    agents' declarations; :data:`OUTSIDE_WRITERS` write some, ``plan result`` reads
    :data:`AFTER_RUN`)."""
    access = access_map(agents)
    lines = ["| entry | type | meaning | written by | read by |", "|---|---|---|---|---|"]
    for key in sorted(entries):
        writers, readers = access.get(key, ([], []))
        if key in OUTSIDE_WRITERS:
            writers = [OUTSIDE_WRITERS[key], *writers]
        if key in AFTER_RUN:
            readers = [*readers, "plan result"]
        entry = entries[key]
        lines.append(
            f"| `{key}` | `{type_name(entry.type)}` | {entry.meaning} | "
            f"{', '.join(writers) or '—'} | {', '.join(readers) or '—'} |"
        )
    return "\n".join(lines)


def planner_access_table() -> str:
    """:func:`access_table` for the default planner's agents (hand3x3, with ``recall``)."""
    from eos_svc.agents.memory import GraspMemory
    from eos_svc.agents.planner import build_agents, build_world
    from eos_svc.schema.request import PlanRequest

    world = build_world(PlanRequest())
    return access_table(build_agents(world, memory=GraspMemory(":memory:")))


#: the lines around the generated table in ``docs/planner.md``
TABLE_BEGIN, TABLE_END = "<!-- board-entries:begin -->", "<!-- board-entries:end -->"


def update_table(path: str) -> bool:
    """Replace the table between :data:`TABLE_BEGIN` and :data:`TABLE_END` in the Markdown file
    ``path`` (a ValidationError without them); whether the file changed."""
    file = Path(path)
    text = file.read_text(encoding="utf-8")
    head, begin, rest = text.partition(TABLE_BEGIN + "\n")
    _, end, tail = rest.partition("\n" + TABLE_END)
    if not begin or not end:
        raise ValidationError("path", f"{path} has no {TABLE_BEGIN} ... {TABLE_END} block")
    new = head + begin + planner_access_table() + end + tail
    if new != text:
        file.write_text(new, encoding="utf-8")
    return new != text


if __name__ == "__main__":  # python -m eos_svc.agents.board_table [docs/planner.md]
    if len(sys.argv) > 1:
        print(f"{sys.argv[1]}: {'updated' if update_table(sys.argv[1]) else 'already current'}")
    else:
        print(planner_access_table())

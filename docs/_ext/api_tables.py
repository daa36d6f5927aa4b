"""Tables of the API page generated from the code, so they list what the code has.

``{collision-fields}``: every field of ``solver.Collision`` (the result of ``solver.collide``) and
every derived observable (a property), with the registry's meaning and units
(solver/observables.py: ``OBSERVABLES``). A field the registry does not describe is listed with
its type.
"""

from __future__ import annotations

import dataclasses

from docutils import nodes
from docutils.parsers.rst import Directive


def _table(header: list[str], rows: list[list[str]], widths: list[int]) -> nodes.table:
    table = nodes.table()
    group = nodes.tgroup(cols=len(header))
    table += group
    group.extend(nodes.colspec(colwidth=w) for w in widths)

    def row(cells, literal_first=True):
        r = nodes.row()
        for k, text in enumerate(cells):
            entry = nodes.entry()
            para = nodes.paragraph()
            para += nodes.literal(text, text) if (k == 0 and literal_first) else nodes.Text(text)
            entry += para
            r += entry
        return r

    head = nodes.thead()
    head += row(header, literal_first=False)
    body = nodes.tbody()
    body.extend(row(cells) for cells in rows)
    group += head
    group += body
    return table


def _type_name(t) -> str:
    return getattr(t, "__name__", str(t))


def collision_rows() -> list[list[str]]:
    from solver import Collision
    from solver.observables import OBSERVABLES

    described = {o.name: o for o in OBSERVABLES}
    rows = []
    for f in dataclasses.fields(Collision):
        o = described.get(f.name)
        if o is None:
            rows.append([f.name, "field", _type_name(f.type), ""])
        else:
            rows.append([f.name, f"field ({o.kind})", o.units, o.long_name])
    rows.extend([o.name, f"property ({o.kind})", o.units, o.long_name]
                for o in OBSERVABLES if o.derived)
    return rows


class CollisionFields(Directive):
    has_content = False

    def run(self):
        return [_table(["name", "kind", "units / type", "meaning"], collision_rows(),
                       [18, 12, 12, 58])]


def setup(app):
    app.add_directive("collision-fields", CollisionFields)
    return {"parallel_read_safe": True, "parallel_write_safe": True}

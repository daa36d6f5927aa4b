"""The model on the site: one page per piece of physics, cut from the one source, docs/model.md.

docs/model.md stays a single file (code comments and tests cite its section headings by name:
``docs/model.md, "Scales"``). At each build its ``##`` sections are written, grouped as
``MODEL_PAGES`` says, to ``docs/model/<slug>.md`` (generated, not in git); the site's ``model``
page becomes the introduction with a table of contents of those pages. Links are rewritten on the
way: ``(#anchor)`` to the page that now holds the heading, ``(other.md)`` one folder up, and
``(model.md#anchor)`` in any other doc to its page. A section of model.md that no page claims,
or a page naming a section model.md does not have, stops the build.
"""

from __future__ import annotations

import re
from pathlib import Path

from myst_parser.mdit_to_docutils.base import default_slugify
from sphinx.errors import ExtensionError

# (slug, title, the ## headings of docs/model.md it holds, in order)
MODEL_PAGES = (
    ("setting", "Setting, equations and scales",
     ("Setting", "Equations", "Scales", "The parameters")),
    ("film", None, ("Film equation",)),
    ("elasticity", None, ("Elasticity",)),
    ("motion-and-energy", "Motion, force and energy", ("Motion and force", "Energy")),
    ("cavitation", None, ("Cavitation",)),
    ("liquid", "Pressure-dependent liquid",
     ("Pressure-dependent viscosity and density", "Rigid piezoviscous film (Barus)")),
    ("limits", "Closed-form limits",
     ("Rigid solution", "Small deformation", "Similarity", "Hertz limit")),
    ("outer-flow", "Outer flow",
     ("Outer flow: the exact Stokes resistance", "Outer flow: the far-field restitution",
      "Outer flow: two unequal spheres", "Outer flow: the whole trajectory",
      "Reading e as experiments do", "Outer flow: the history force")),
    ("roughness", "Rough surfaces and losses in the solids",
     ("Surface roughness", "Losses in the solids")),
    ("slip", None, ("Slip",)),
    ("observables", "Observables and figures", ("Observables", "Figures")),
    ("adding-a-term", None, ("How to add a term",)),
    ("glossary", None, ("Glossary",)),
    ("references", None, ("References",)),
)

GENERATED = "model"  # the folder, under docs/, of the generated pages
_MODEL: dict = {}  # model.md's introduction and anchors, read once per build (config-inited)
LINK = re.compile(r"\]\(([^)\s]+)\)")
HEADING = re.compile(r"^(#{1,6}) (.*)$")


def split_sections(text: str) -> tuple[str, dict[str, str]]:
    """The introduction (before the first ``##``) and each ``##`` section's text by heading."""
    intro, sections, current = [], {}, None
    for line in text.splitlines(keepends=True):
        m = HEADING.match(line)
        if m and len(m.group(1)) == 2:
            current = m.group(2).strip()
            if current in sections:
                raise ExtensionError(f"docs/model.md: two sections named {current!r}")
            sections[current] = ""
        if current is None:
            intro.append(line)
        else:
            sections[current] += line
    return "".join(intro), sections


def anchor_pages(sections: dict[str, str]) -> dict[str, str]:
    """Anchor of every heading (any level) -> the slug of the page that holds it."""
    page_of = {h: slug for slug, _, heads in MODEL_PAGES for h in heads}
    anchors = {}
    for head, body in sections.items():
        for line in body.splitlines():
            m = HEADING.match(line)
            if m:
                anchors[default_slugify(m.group(2).strip())] = page_of[head]
    return anchors


def check_pages(sections: dict[str, str]) -> None:
    claimed = [h for _, _, heads in MODEL_PAGES for h in heads]
    unclaimed = [h for h in sections if h not in claimed]
    unknown = [h for h in claimed if h not in sections]
    if unclaimed or unknown:
        raise ExtensionError(
            f"docs/_ext/model_pages.py MODEL_PAGES and docs/model.md disagree: sections no page "
            f"holds: {unclaimed}; sections model.md does not have: {unknown}")


def rewrite_links(text: str, anchors: dict[str, str], here: str | None) -> str:
    """Links of model.md's text as seen from page ``here`` (a slug; None: the model index)."""

    def sub(m):
        target = m.group(1)
        if "://" in target or target.startswith("mailto:"):
            return m.group(0)
        if target.startswith("#"):
            page = anchors.get(target[1:])
            if page is None or page == here:
                return m.group(0)  # unknown anchors are left for Sphinx to report
            prefix = "" if here is not None else f"{GENERATED}/"
            return f"]({prefix}{page}.md{target})"
        if here is not None:
            return f"](../{target})"
        return m.group(0)

    return LINK.sub(sub, text)


def page_text(slug: str, title: str | None, heads: tuple[str, ...], sections: dict[str, str],
              anchors: dict[str, str]) -> str:
    body = "".join(sections[h] for h in heads)
    if title is None:  # one section: its heading is the page's title, every level one up
        body = re.sub(r"^#(#+ )", r"\1", body, flags=re.M)
    else:
        body = f"# {title}\n\n{body}"
    names = ", ".join(f'"{h}"' for h in heads)
    return (f"<!-- generated from docs/model.md by docs/_ext/model_pages.py: edit docs/model.md -->\n"
            f"{rewrite_links(body, anchors, slug)}\n"
            f"*Source: docs/model.md, {names}.*\n")


def index_text(intro: str, anchors: dict[str, str]) -> str:
    pages = "\n".join(f"{GENERATED}/{slug}" for slug, _, _ in MODEL_PAGES)
    return (f"{rewrite_links(intro, anchors, None)}\n"
            f"```{{toctree}}\n:maxdepth: 2\n\n{pages}\n```\n")


def _write_if_changed(path: Path, text: str) -> None:
    if not path.exists() or path.read_text() != text:
        path.write_text(text)


def write_pages(app, config) -> None:
    src = Path(app.srcdir)
    intro, sections = split_sections((src / "model.md").read_text())
    check_pages(sections)
    anchors = anchor_pages(sections)
    out = src / GENERATED
    out.mkdir(exist_ok=True)
    wanted = set()
    for slug, title, heads in MODEL_PAGES:
        path = out / f"{slug}.md"
        wanted.add(path.name)
        _write_if_changed(path, page_text(slug, title, heads, sections, anchors))
    for stale in out.glob("*.md"):
        if stale.name not in wanted:
            stale.unlink()
    _MODEL.update(intro=intro, anchors=anchors)


def replace_sources(app, docname, source) -> None:
    """The ``model`` page becomes its introduction and contents; every other doc's links to
    ``model.md#anchor`` go to the page that holds the anchor."""
    intro, anchors = _MODEL["intro"], _MODEL["anchors"]
    if docname == "model":
        source[0] = index_text(intro, anchors)
        return
    def sub(m):
        target = m.group(1)
        base, _, anchor = target.partition("#")
        if not anchor or not base.endswith("model.md") or docname.startswith(f"{GENERATED}/"):
            return m.group(0)
        page = anchors.get(anchor)
        if page is None:
            return m.group(0)
        return f"]({base[:-len('model.md')]}{GENERATED}/{page}.md#{anchor})"

    source[0] = LINK.sub(sub, source[0])


def setup(app):
    app.connect("config-inited", write_pages)
    app.connect("source-read", replace_sources)
    return {"parallel_read_safe": True, "parallel_write_safe": True}

"""The docs cover the code: every module has its row in docs/architecture.md."""

from pathlib import Path

REPO = Path(__file__).resolve().parent.parent


def test_every_module_is_in_the_architecture_table():
    doc = (REPO / "docs" / "architecture.md").read_text()
    missing = []
    for package in ("solver", "pipeline"):
        for path in sorted((REPO / package).rglob("*.py")):
            if path.name == "__init__.py":
                continue
            rel = path.relative_to(REPO / package).as_posix()
            if f"`{rel}`" not in doc:
                missing.append(f"{package}/{rel}")
    assert not missing, f"add a row to docs/architecture.md for {missing}"


# ---- the README's commands and samples against the code (issue 20: they had drifted) ---------
import argparse  # noqa: E402
import math  # noqa: E402
import re  # noqa: E402

import pytest  # noqa: E402

DOCS = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]


def _subparser(name: str) -> argparse.ArgumentParser:
    from pipeline import cli

    parser = cli._parser([name])
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return sub.choices[name]


def _documented_commands():
    """Every ``ehd COMMAND ...`` the docs show: code-block lines (``ehd``, ``$ ehd``,
    ``.venv/bin/ehd``) and inline code spans, as ``(doc, text)``."""
    found = []
    for doc in DOCS:
        text = doc.read_text()
        for line in text.splitlines():
            m = re.match(r"^\s*(?:\$ |\.venv/bin/)?(ehd [^#]*)", line)
            if m:
                found.append((doc.name, m.group(1)))
        for span in re.findall(r"`([^`\n]*)`", text):
            m = re.match(r"(?:\.venv/bin/)?(ehd [a-z].*)", span)
            if m:
                found.append((doc.name, m.group(1)))
    return found


def test_every_documented_command_and_flag_exists():
    from pipeline.cli import COMMANDS

    commands = _documented_commands()
    assert len(commands) > 30  # the README and docs show many; a broken extraction finds none
    unknown = []
    parsers = {}
    for doc, text in commands:
        # ehd sweep A && ehd figures B: each command on its own
        for part in re.split(r"&&|;", text):
            words = part.split()
            if len(words) < 2 or words[0] != "ehd":
                continue
            name = words[1]
            if name.startswith("-"):
                if name not in ("--help", "--version"):
                    unknown.append(f"{doc}: {part.strip()}: {name}")
                continue
            if name not in COMMANDS:
                unknown.append(f"{doc}: {part.strip()}: no command {name!r}")
                continue
            if name not in parsers:
                parsers[name] = set(_subparser(name)._option_string_actions)
            for word in words[2:]:
                for flag in re.findall(r"(?<![\w-])--[A-Za-z][\w-]*", word):
                    if flag not in parsers[name]:
                        unknown.append(f"{doc}: {part.strip()}: {name} has no {flag}")
    assert not unknown, "\n".join(unknown)


def test_documented_python_names_exist():
    """``pipeline.x.y`` and ``solver.x.y`` in the docs are modules or their attributes."""
    import importlib

    missing = []
    for doc in DOCS:
        for dotted in sorted(set(re.findall(r"\b(?:pipeline|solver)(?:\.[A-Za-z_]\w*)+",
                                            doc.read_text()))):
            parts = dotted.split(".")
            for k in range(len(parts), 0, -1):  # the longest importable module prefix
                try:
                    obj = importlib.import_module(".".join(parts[:k]))
                except ImportError:
                    continue
                break
            try:
                for attr in parts[k:]:
                    obj = getattr(obj, attr)
            except AttributeError:
                # a file name (``solver/physics.py`` written with dots) is not a Python name
                if not (REPO / "/".join(parts[:k])).with_suffix(".py").exists() and \
                        not parts[-1] in ("py", "md", "toml", "json", "csv", "png"):
                    missing.append(f"{doc.name}: {dotted}")
    assert not missing, missing


def _doc_block(after: str, doc: str = "docs/solver.md") -> list[str]:
    text = (REPO / doc).read_text()
    start = text.index(after) + len(after)
    return text[start:text.index("```", start)].strip("\n").splitlines()


def test_solver_doc_ehd_run_sample_is_what_ehd_run_prints(capsys):
    from pipeline.cli import main, report_rows

    assert main(["run", "--St", "10", "--eps", "0.01"]) == 0
    printed = capsys.readouterr().out.splitlines()
    sample = _doc_block("$ ehd run --St 10 --eps 0.01\n")
    label = re.compile(r"^(.*?\S)\s{2,}(\S.*)$")
    got = [label.match(line).groups() for line in printed]
    shown = [label.match(line).groups() for line in sample]
    assert [k for k, _ in shown] == [k for k, _ in got]  # every row, in the order printed
    assert len(got) == len(report_rows({k: None for k in _json_keys()}))
    for (k, want), (_, have) in zip(shown, got):
        if k in ("steps", "rejected", "wall time [s]"):
            continue  # time-loop counts move with the CPU's round-off; the wall time with load
        try:
            w, h = float(want), float(have)
        except ValueError:
            assert want == have, k
            continue
        # printed to 6 digits; another CPU's round-off moves a result by less than the standard
        # preset's target error (benchmarks/accuracy.md: 0.005; its largest on h_m is 1.1e-02)
        assert math.isclose(w, h, rel_tol=5e-3, abs_tol=1e-12), (k, want, have)


def _same_numbers(want: str, have: str) -> bool:
    """Two printed lines alike, word by word, their numbers within the tolerance of the sample
    test above (another CPU's round-off, below the standard preset's target error)."""
    a, b = want.split(), have.split()
    if len(a) != len(b):
        return False
    for w, h in zip(a, b):
        try:
            if not math.isclose(float(w), float(h), rel_tol=5e-3, abs_tol=1e-12):
                return False
        except ValueError:
            if w != h:
                return False
    return True


@pytest.mark.parametrize("command", ["ehd run --St 10 --eps 0.01",
                                     "ehd restitution examples/glass_beads_water.toml --n 5 "
                                     "--accuracy fast"])
def test_readme_samples_are_what_the_commands_print(capsys, monkeypatch, command):
    """Every line the README shows under ``$ <command>`` (``...`` leaves lines out) is a line
    the command prints, in that order (its numbers had drifted from an older solver)."""
    from pipeline.cli import main

    monkeypatch.chdir(REPO)
    assert main(command.split()[1:]) == 0
    printed = capsys.readouterr().out.splitlines()
    sample = [line for line in _doc_block(f"$ {command}\n", "README.md") if line != "..."]
    assert len(sample) >= 4
    at = 0
    for line in sample:
        found = next((k for k in range(at, len(printed)) if _same_numbers(line, printed[k])),
                     None)
        assert found is not None, (line, printed)
        at = found + 1
    if command.startswith("ehd run"):  # and exactly docs/solver.md's sample of the same run
        solver_doc = _doc_block(f"$ {command}\n")
        assert all(line in solver_doc for line in sample if line.strip() != "..."), sample


def _json_keys():
    from solver import JSON_KEYS

    return JSON_KEYS


def test_documented_json_key_order_is_the_code_order():
    from solver.physics import Physics

    keys = list(_json_keys())
    text = " ".join((REPO / "docs" / "solver.md").read_text().split())
    para = text[text.index("`--json` prints exactly one JSON object"):]
    para = para[:para.index("`solver.JSON_KEYS`")]
    runs = [[k.strip() for k in span.split(",") if k.strip() not in ("", "...")]
            for span in re.findall(r"`([^`]*)`", para) if "," in span]
    assert len(runs) >= 4
    position = -1
    for run in runs:  # each listed run is consecutive in JSON_KEYS, the runs in that order
        i = keys.index(run[0])
        assert keys[i:i + len(run)] == run, run
        assert i > position, run
        position = i
    assert runs[0][:2] == list(Physics.names()[:2])


def test_every_option_has_help_with_its_default():
    from pipeline.cli import COMMANDS

    bad = []
    for name in COMMANDS:
        for action in _subparser(name)._actions:
            if isinstance(action, argparse._HelpAction):
                continue
            text = action.help or ""
            if not text or text == argparse.SUPPRESS:
                bad.append(f"ehd {name} {'/'.join(action.option_strings) or action.dest}: no help")
            elif (action.option_strings and not action.required
                  and action.default not in (None, False, "", argparse.SUPPRESS)
                  and "default" not in text.lower()):
                bad.append(f"ehd {name} {action.option_strings[0]}: default not in help")
    assert not bad, bad


def test_the_registry_is_the_one_list_of_commands():
    """Each module's ``register`` adds exactly the commands the registry assigns to it."""
    import importlib

    from pipeline.cli import COMMAND_MODULES, COMMANDS

    class Recorder:
        def __init__(self):
            self.names = []

        def add_parser(self, name, **kwargs):
            self.names.append(name)
            return argparse.ArgumentParser(add_help=False)

    for module in COMMAND_MODULES:
        rec = Recorder()
        importlib.import_module(module).register(rec)
        assert rec.names == [n for n, (m, _) in COMMANDS.items() if m == module], module


def test_python_example_runs_from_a_copy_of_the_examples(tmp_path):
    """examples/scene_in_python.py, as a newcomer runs it (from a folder of ``ehd examples``)."""
    import shutil
    import subprocess
    import sys

    shutil.copytree(REPO / "examples", tmp_path / "examples")
    p = subprocess.run([sys.executable, "examples/scene_in_python.py"], cwd=tmp_path,
                       capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr[-2000:]
    assert "sticking threshold in e_wet (resolved CFD-DEM): St_c = " in p.stdout and "e_wet = " in p.stdout


# ---- cited headings and links resolve (the site cuts docs/model.md into pages by heading) -------
CITING = [REPO / "README.md", REPO / "Makefile", *sorted((REPO / "docs").glob("*.md")),
          *(p for d in ("solver", "pipeline", "tests", "benchmarks", "examples", "sweeps")
            for p in sorted((REPO / d).rglob("*")) if p.suffix in (".py", ".md", ".toml"))]


def _headings(doc: Path, labels: bool = False) -> list[str]:
    """The heading texts of a Markdown file, outside code blocks, without backticks; with
    ``labels``, also the bold labels that open a paragraph or an item (``**Surface roughness**``)."""
    pattern = r"#{1,6} (.*)" + (r"|(?:- )?\*\*([^*]+)\*\*" if labels else "")
    out, fenced = [], False
    for line in doc.read_text().splitlines():
        if line.startswith("```"):
            fenced = not fenced
        elif not fenced and (m := re.match(pattern, line)):
            out.append(next(g for g in m.groups() if g).replace("`", "").strip())
    return out


def _slug(heading: str) -> str:
    """GitHub's (and myst-parser's) anchor of a heading."""
    return re.sub(r"\s", "-", re.sub(r"[^\w\s-]", "", heading.strip().lower()))


# a cited heading: ``docs/NAME.md, "Heading"`` (or ``NAME.md "Heading"``, a benchmark file
# ``benchmarks/NAME.md``, "Heading"), and ``docs/NAME.md ("Heading", "Another")``
CITE_HEADING = re.compile(r'((?:docs/|benchmarks/)?\w+\.md)`?(?:,[ \t]*|[ \t]+)'
                          r'(?:\n[ \t]*(?:#[ \t]*)?)?"([^"]{2,120})"')
CITE_HEADINGS = re.compile(r'((?:docs/|benchmarks/)?\w+\.md)\)?[ \t]*\('
                           r'((?:"[^"]{2,120}"(?:,[ \t]*)?)+)\)')


def _cited_headings(text: str):
    """``(file, heading)`` of every heading citation in ``text``, the file resolved (a bare
    ``NAME.md`` is docs/NAME.md)."""
    for name, quoted in CITE_HEADING.findall(text):
        yield name, quoted
    for name, quoted in CITE_HEADINGS.findall(text):
        for one in re.findall(r'"([^"]+)"', quoted):
            yield name, one


def test_cited_headings_exist():
    """``docs/NAME.md, "Heading"`` anywhere in the code, tests or docs names a heading of that
    file, or the start of one (``"Outer flow"``), or a paragraph's bold label; a moved or
    renamed section fails here. The same for ``docs/NAME.md ("A", "B")`` and for the
    headings of benchmark result files (``benchmarks/NAME.md``, "Heading")."""
    found, bad = 0, []
    for path in CITING:
        for name, quoted in _cited_headings(path.read_text()):
            doc = REPO / name if name.startswith("benchmarks/") else \
                REPO / "docs" / Path(name).name
            if not doc.exists():
                continue
            wanted = " ".join(re.sub(r"\n[ \t]*#?[ \t]*", " ", quoted).split()).replace("`", "")
            found += 1
            if not any(h.lower().startswith(wanted.lower()) for h in _headings(doc, labels=True)):
                bad.append(f"{path.relative_to(REPO)}: {doc.relative_to(REPO)} has no heading "
                           f"{wanted!r}")
    assert found > 50, found  # the code cites many; a broken pattern finds none
    assert not bad, "\n".join(bad)


def test_relative_links_between_docs_resolve():
    """``[text](other.md#anchor)`` and ``(#anchor)`` in README and docs/ point at a file that
    exists and a heading it has (``make docs`` fails on the same, with warnings as errors)."""
    bad = []
    for doc in DOCS:
        for target in re.findall(r"\]\(([^)\s]+)\)", doc.read_text()):
            if "://" in target or target.startswith("mailto:"):
                continue
            path, _, anchor = target.partition("#")
            if doc.parent.name == "docs" and path.startswith(("gallery/", "model/")):
                continue  # pages make docs generates (it checks those links itself)
            dest = (doc.parent / path) if path else doc
            if not dest.exists():
                bad.append(f"{doc.name}: {target}: no file {path}")
            elif anchor and dest.suffix == ".md" and anchor not in map(_slug, _headings(dest)):
                bad.append(f"{doc.name}: {target}: no heading with anchor #{anchor}")
    assert not bad, "\n".join(bad)


def test_api_page_documents_the_entry_points():
    """The site's API page (docs/api.md) renders what a user calls and what they get back."""
    page = (REPO / "docs" / "api.md").read_text()
    for directive in (".. autofunction:: solver.collide", ".. autoclass:: solver.Physics",
                      ".. autoclass:: solver.Collision", "{collision-fields}",
                      ".. autofunction:: pipeline.open_results"):
        assert directive in page, directive


# ---- numbers the docs quote from the benchmark result files (benchmarks/*.json) ---------------
# A quoted number agrees with its source when it is the source's value rounded to the digits
# quoted: a re-run of the benchmark that moves a number fails here until the docs say the new one.
def _bench(name: str) -> dict:
    import json

    return json.loads((REPO / "benchmarks" / f"{name}.json").read_text())


def _quoted_matches(quoted: str, value: float) -> bool:
    """``"1.6"``, ``"0.47"``, ``"1.3e-3"``, ``"19"`` against ``value`` (same units): equal to
    the value rounded to the quoted digits."""
    mantissa, _, exponent = quoted.lower().partition("e")
    decimals = len(mantissa.partition(".")[2])
    step = 10.0 ** (int(exponent or 0) - decimals)
    return abs(float(quoted) - value) <= 0.5 * step * (1 + 1e-9)


def _accuracy_maxima(preset: str) -> dict:
    """Largest error of each observable over the panel, and over its scenes with St <= 30."""
    acc = _bench("accuracy")
    row = acc["table"][preset]
    small = [St <= 30 for St, _ in acc["panel"]]
    out = {"wall_ms": row["wall_median"] * 1e3}
    for obs, errors in row["errors"].items():
        out[obs] = max(errors)
        out[obs + "_st30"] = max(e for e, s in zip(errors, small) if s)
    return out


def _docs_text() -> dict[str, str]:
    return {doc.name: doc.read_text() for doc in DOCS}


def test_preset_tables_quote_benchmarks_accuracy_json():
    """Each preset table (header ``| preset | v_r |``, README's "What each preset buys") quotes
    benchmarks/accuracy.json: max errors in %, St <= 30 with the whole panel in brackets, and
    the median wall time per collision in ms."""
    columns = (("v_r",), ("h_m_x1_st30", "h_m_x1"), ("h_m_approach_x1_st30", "h_m_approach_x1"),
               ("ln_x_e_x1_st30", "ln_x_e_x1"), ("wall_ms",))
    tables, bad = 0, []
    for name, text in _docs_text().items():
        for table in re.findall(r"^\| preset \| v_r \|.*\n\|[-| ]+\|\n((?:\|.*\|\n)+)", text, re.M):
            tables += 1
            for line in table.splitlines():
                cells = [c.strip() for c in line.strip("|").split("|")]
                preset = cells[0].strip("`")
                want = _accuracy_maxima(preset)
                assert len(cells) == 1 + len(columns), line
                for keys, cell in zip(columns, cells[1:]):
                    numbers = re.findall(r"\d+(?:\.\d+)?", cell)
                    assert len(numbers) == len(keys), (name, line, cell)
                    for key, quoted in zip(keys, numbers):
                        value = want[key] * (1 if key == "wall_ms" else 100)
                        if not _quoted_matches(quoted, value):
                            bad.append(f"{name}: {preset} {key}: quoted {quoted}, "
                                       f"benchmarks/accuracy.json {value:.3g}")
    assert tables >= 1, "no doc quotes the preset table of benchmarks/accuracy.json any more"
    assert not bad, "\n".join(bad)


def _piezoviscous_cost(preset: str, variants: tuple) -> list[float]:
    """Median per-scene time ratio to the classic film (benchmarks/piezoviscous.json), by the
    benchmark's own definition (bench_piezoviscous.ratios)."""
    import importlib
    import statistics
    import sys

    sys.path.insert(0, str(REPO / "benchmarks"))
    try:
        bench = importlib.import_module("bench_piezoviscous")
    finally:
        sys.path.remove(str(REPO / "benchmarks"))
    speed = _bench("piezoviscous")["speed"]
    return [statistics.median(bench.ratios(speed, preset, v)) for v in variants]


# (what is quoted, a pattern over a doc's text with its whitespace collapsed whose groups are the
#  numbers, and the source value of each group, in the units quoted)
QUOTES = [
    ("the standard preset's largest errors (docs/scenes.md, viscosity switch)",
     r"standard: largest errors (\S+) on `v_r`, (\S+) on `h_m`, (\S+) on `h_m` on approach",
     lambda: [_accuracy_maxima("standard")[k] for k in ("v_r", "h_m_x1", "h_m_approach_x1")]),
    ("the pressure-dependent liquid's cost against the classic film, standard preset "
     "(benchmarks/piezoviscous.json)",
     r"(\d+\.\d)x at beta = 1, (\d+\.\d)x at 2, (\d+\.\d)x at 5, (\d+\.\d)x at 10[;( ]+"
     r"Roelands at 5: (\d+\.\d)x[;,] (?:Barus )?with Dowson-Higginson:? (\d+\.\d)x",
     lambda: _piezoviscous_cost("standard", ("barus-1", "barus-2", "barus-5", "barus-10",
                                             "roelands-5", "barus-dh-5"))),
]


@pytest.mark.parametrize("what, pattern, source", QUOTES, ids=[q[0] for q in QUOTES])
def test_quoted_benchmark_numbers_are_the_result_files(what, pattern, source):
    values = source()
    found = 0
    for name, text in _docs_text().items():
        for groups in re.findall(pattern, " ".join(text.split())):
            groups = (groups,) if isinstance(groups, str) else groups
            found += 1
            for quoted, value in zip(groups, values):
                assert _quoted_matches(quoted, value), \
                    f"{name}: {what}: quoted {quoted}, the benchmark's result {value:.4g}"
    assert found, f"no doc quotes {what} any more: quote it again or drop it from QUOTES"


# ---- cited measurements exist (issue 28: one measurement was cited as 20x and as 30x, from two
# files that held neither) ---------------------------------------------------------------------
# The form: ``FILE: NUMBERS`` where FILE is a benchmark result or a doc (``benchmarks/NAME.md``,
# ``benchmarks/NAME.json``, ``docs/NAME.md``) and NUMBERS runs to the next ``)``, ``;`` or sentence
# end, e.g. "(benchmarks/accuracy.md: 0.005)" or with several numbers "1.69, 2.08". Every number
# in it must be in FILE, to the digits quoted (a percentage also as a fraction).
CITED = re.compile(r"\b((?:benchmarks|docs)/\w+\.(?:md|json)): ([^);]{1,120}?)(?=[);]|\.\s|\.$|$)")
DIGITS = re.compile(r"(?<![\w.])\d+(?:\.\d+)?(?:[eE][-+]?\d+)?(?![\w.]*\d)")


def _measurement_citations():
    """``(citing file, cited file, quoted number, percent)`` of every citation in that form."""
    out = []
    for path in CITING:
        text = " ".join(re.sub(r"\n[ \t]*#?[ \t]*", " ", path.read_text()).split())
        for cited, span in CITED.findall(text):
            for m in DIGITS.finditer(span):
                percent = span[m.end():].lstrip().startswith("%")
                out.append((path.relative_to(REPO).as_posix(), cited, m.group(0), percent))
    return out


def test_cited_measurements_exist():
    """A number cited from a file is in that file: a re-run benchmark that moves it, or a
    citation of the wrong file, fails here until the citation says what the file holds."""
    citations = _measurement_citations()
    assert len(citations) >= 10, citations  # the docs and code cite that many; a broken pattern none
    bad = []
    for citing, cited, quoted, percent in citations:
        held = [float(n) for n in DIGITS.findall((REPO / cited).read_text())]
        if not any(_quoted_matches(quoted, v) or (percent and _quoted_matches(quoted, 100 * v))
                   for v in held):
            bad.append(f"{citing}: {cited} does not hold {quoted}{' %' if percent else ''}")
    assert not bad, "\n".join(bad)


def test_the_scene_json_table_has_every_key():
    """docs/scenes.md, "JSON output" lists every key of ``ehd scene --json`` (RESULT_KEYS)."""
    from pipeline.scenes.run import RESULT_KEYS

    text = (REPO / "docs" / "scenes.md").read_text()
    table = text[text.index("## JSON output"):]
    table = table[:table.index("\n## ")]
    listed = set(re.findall(r"`(\w+)`", table))
    assert not set(RESULT_KEYS) - listed, set(RESULT_KEYS) - listed


def test_the_store_variables_table_has_every_variable():
    """docs/pipeline.md, "Variables" lists every variable a sweep store holds (``e_far`` and
    ``v_outer_start`` were missing; a hostile scan)."""
    from pipeline.sweeps.layout import VARIABLES

    text = (REPO / "docs" / "pipeline.md").read_text()
    table = text[text.index("### Variables"):]
    table = table[:table.index("\n#")]
    listed = set(re.findall(r"`(\w+)`", table))
    assert not set(VARIABLES) - listed, set(VARIABLES) - listed


def _scenes_doc_section(heading: str) -> str:
    text = (REPO / "docs" / "scenes.md").read_text()
    section = text[text.index(heading):]
    return section[:section.index("\n## ", 1)]


def test_the_scene_docs_list_every_material_check_flag_and_input():
    """docs/scenes.md names every shipped material and fluid, every validity check, every flag
    of ``ehd scene`` and every key of the JSON ``inputs``: four lists had fallen behind the code
    (delrin, nylon, four liquids; the roughness check; --asperity-contact, --e-dry;
    roughness_m, approach_speed_source; a documentation check)."""
    from pipeline.cli_shared import add_numerics_flags
    from pipeline.scenes.checks import THRESHOLDS
    from pipeline.scenes.commands import load_scene
    from pipeline.scenes.materials import load_table

    text = (REPO / "docs" / "scenes.md").read_text()
    named = set(re.findall(r"`([\w.-]+)`", text))
    table = load_table(user_files=False)
    shipped = set(table.solids) | set(table.fluids)
    assert not shipped - named, shipped - named
    rows = set(re.findall(r"^\| `(\w+)`", text, re.M))  # the first column of its tables
    assert not set(THRESHOLDS) - rows, set(THRESHOLDS) - rows
    numerics = argparse.ArgumentParser()
    add_numerics_flags(numerics)  # "the numerical flags of ehd run apply too"
    flags = {o for a in _subparser("scene")._actions for o in a.option_strings
             if o.startswith("--")} - {o for a in numerics._actions for o in a.option_strings}
    flags = {f for f in flags if not (f.endswith("2") and f[:-1] + "1" in flags)}  # "...2"
    mentioned = set(re.findall(r"(--[a-z][\w-]*)", text))
    assert not flags - mentioned - {"--help"}, flags - mentioned
    inputs = load_scene(str(REPO / "examples" / "glass_beads_water.toml"), {}).inputs()
    keys = set(inputs) | set(inputs["body1"]) | set(inputs["fluid"])
    assert not keys - named, keys - named

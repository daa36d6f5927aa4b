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
        # printed to 6 digits; another CPU's round-off moves a result within the preset's own
        # accuracy at most (standard: 0.5 % on h_m, benchmarks/accuracy.md)
        assert math.isclose(w, h, rel_tol=5e-3, abs_tol=1e-12), (k, want, have)


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
    assert "sticking threshold: St_c = " in p.stdout and "e_wet = " in p.stdout

"""The README is the front page (issue 29): short, the user's path first, and every sample
output in it is what the program prints now.

A sample is a fenced block whose first line is ``$ ehd ...``: the command runs (in-process, from
the clone's folder), and every line the block shows must appear in its output, in that order.
A line ``...`` stands for any number of lines. Numbers are compared within 5e-3 relative: another
CPU's round-off moves a result by less than the standard preset's target error
(benchmarks/accuracy.md: 0.005; its largest on h_m is 1.1e-02); every other character must match.
"""

import math
import os
import re
import shlex
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent
README = (REPO / "README.md").read_text()
NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def _samples():
    blocks = re.findall(r"```[a-z]*\n(.*?)```", README, flags=re.S)
    return [b.splitlines() for b in blocks if b.startswith("$ ehd ")]


def _same(shown: str, printed: str) -> bool:
    """Equal text, numbers within 5e-3 relative (whitespace runs count as one)."""
    shown, printed = " ".join(shown.split()), " ".join(printed.split())
    if NUMBER.sub("#", shown) != NUMBER.sub("#", printed):
        return False
    for a, b in zip(NUMBER.findall(shown), NUMBER.findall(printed)):
        if not math.isclose(float(a), float(b), rel_tol=5e-3, abs_tol=1e-12):
            return False
    return True


def test_the_readme_is_a_front_page():
    """Under 200 lines; the scene format, which e to take and how to export it in the first 80
    (issue 29: they were at lines 495, 188 and 253 of 613); it starts with the two commands."""
    lines = README.splitlines()
    assert len(lines) < 200
    head = "\n".join(lines[:80])
    assert "[body1]" in head and "material = " in head  # a scene file
    assert "e for a dry DEM code (e_far)" in head and "Which restitution to take" in head
    assert "ehd export-dem" in head
    assert lines[3:5] == ["make sweep    # creates .venv, installs, runs the default sweep: "
                          "store results/paper.zarr + figures/",
                          "make test     # creates .venv if needed, runs the test suite"]


def test_the_readme_has_samples():
    assert len(_samples()) >= 3


@pytest.mark.parametrize("sample", _samples(), ids=lambda s: s[0][2:40])
def test_every_readme_sample_is_what_the_program_prints(sample, capsys, monkeypatch):
    from pipeline.cli import main

    monkeypatch.chdir(REPO)
    argv = shlex.split(sample[0][2:])[1:]
    assert main(argv) == 0
    printed = capsys.readouterr().out.splitlines()
    at = 0
    skipping = False
    for shown in sample[1:]:
        if shown.strip() == "...":
            skipping = True
            continue
        while at < len(printed) and not _same(shown, printed[at]):
            assert skipping, f"after line {at}: shown {shown!r}, printed {printed[at]!r}"
            at += 1
        assert at < len(printed), f"{shown!r} is not in the output of {sample[0]!r}"
        at += 1
        skipping = False


def test_readme_links_exist():
    for target in re.findall(r"\]\(([^)#]+)\)", README):
        assert (REPO / target).exists(), target

"""The Steps tab cites the paper as the paper is numbered: every step title's equations are read
from the paper's LaTeX source (``../shared/paper/cbm-paper.tex``), each numbered ``equation`` and
``align`` in order, and found there by what they state."""
from __future__ import annotations

import re
from pathlib import Path

import pytest

from app.walkthrough.steps import NAMES

PAPER = Path(__file__).resolve().parents[3] / "shared" / "paper" / "cbm-paper.tex"
NUMBERED = re.compile(r"\\begin\{(equation|align)\}(.*?)\\end\{\1\}", re.S)

STATES = {
    "pose": [r"\widetilde{\bm{T}}_c^e=f"],
    "context": [r"\boldsymbol{z}_{ii'}^{\bm{p}} &=", r"\bm{P}_i&="],
    "local": [r"{S}_{\bm{z}}=\frac{\alpha}{\sigma_1}"],
    "candidates": [r"\bm{L}_{ij}(i',j')=\left\{"],
    "consensus": [r"\bm{G}_{ij}(i',j')=\left\{", r"\bm{L}_{ij}^{(1)}=\bm{G}_{ij} \circ \bm{L}_{ij}"],
    "anchor": [r"\bm{L}^{(2)}_{ij}(i',j')=", r"\bm{M}=\arg \max", r"\hat{\mathcal{M}}=\{(i,j)"],
    "estimate": [r"\psi \left(", r"\hat{\bm{T}}_c^e = \begin{bmatrix}"],
}
"""What each step's equations state, as the paper writes them (whitespace aside)."""


def squeezed(text: str) -> str:
    return re.sub(r"\s+", "", text)


def paper_numbers() -> list[str]:
    """The paper's numbered displays in order: display k holds equation k + 1."""
    if not PAPER.is_file():
        pytest.skip("../shared/paper/cbm-paper.tex is not beside the repository")
    return [squeezed(body) for _, body in NUMBERED.findall(PAPER.read_text())]


def cited(equations: str) -> list[int]:
    """The equation numbers a title cites: "eq. 10-11" gives [10, 11]."""
    found = re.fullmatch(r"eq\. (\d+)(?:-(\d+))?", equations)
    assert found, f"{equations!r} is not an equation citation"
    first, last = int(found[1]), int(found[2] or found[1])
    return list(range(first, last + 1))


def test_the_paper_has_its_sixteen_numbered_equations() -> None:
    assert len(paper_numbers()) == 16


@pytest.mark.parametrize("key, name, equations", [n for n in NAMES if n[0] in STATES], ids=lambda v: str(v))
def test_a_step_title_cites_the_equations_that_state_its_step(key: str, name: str, equations: str) -> None:
    displays = paper_numbers()
    where = sorted({k + 1 for statement in STATES[key] for k, body in enumerate(displays)
                    if squeezed(statement) in body})
    assert len(where) == len(STATES[key]), f"{name}: not every statement was found once in the paper"
    assert cited(equations) == where, f"'{name}' cites {equations}; the paper states it in eq. {where}"


def test_steps_beyond_the_paper_borrow_no_number_of_it() -> None:
    beyond = [n for n in NAMES if n[0] not in STATES]
    assert {n[0] for n in beyond} == {"reassociate", "result", "over_time"}
    assert all("eq." not in equations for _, _, equations in beyond)
    assert all("beyond the paper" in equations for key, _, equations in beyond if key != "result")

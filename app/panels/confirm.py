"""A question asked before a change: a modal window with the words and one button per answer."""
from __future__ import annotations

from collections.abc import Callable, Mapping

import viser
from viser._gui_handles import GuiModalHandle

from ..session.markup import no_html


def ask(gui: viser.GuiApi, title: str, markdown: str, answers: Mapping[str, Callable[[], None] | None]) -> None:
    """Ask in a modal window; each answer's button closes it and calls its action (None: nothing)."""
    with gui.add_modal(title) as modal:
        gui.add_markdown(no_html(markdown))
        buttons = {answer: gui.add_button(answer, color=None if k == 0 else "gray")
                   for k, answer in enumerate(answers)}
    for answer, button in buttons.items():
        button.on_click(lambda e, act=answers[answer]: _answered(modal, act))


def _answered(modal: GuiModalHandle, act: Callable[[], None] | None) -> None:
    modal.close()
    if act is not None:
        act()

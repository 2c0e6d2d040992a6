"""User text in the page's markdown: shown as written, never as markup.

viser renders the HTML inside markdown as is (its client parses raw HTML without sanitising it), so
a preset's name, a dataset's ids or a typed value that reached a markdown panel could add elements
and run scripts in every tab that shows it (issue 50, item 1). The app's own markdown holds no HTML
and no image, so every ``<`` and ``![`` a markdown panel receives is turned into text (``no_html``,
applied by ``app.panels.actions.assign``); a user's string set inside the app's markdown is also
escaped as text (``plain``), so that it cannot start a link, an emphasis, a code span or a table
cell either."""
from __future__ import annotations

import re

PUNCTUATION = re.compile(r"([\\`*_{}\[\]()#+\-.!|~>])")
"""ASCII punctuation that may start markdown (CommonMark lets a backslash escape any of it)."""
BREAKS = re.compile(r"[\x00-\x1f\x7f\u2028\u2029]+")


def no_html(markdown: str) -> str:
    """``markdown`` with every ``<`` written as the entity ``&lt;`` (no raw HTML, comment or
    autolink can start; the text still reads ``<``) and no image: viser's server replaces
    ``![..](path)`` by the image file at ``path``, any file it can read, before sending it."""
    return markdown.replace("<", "&lt;").replace("![", "!\\[")


def plain(text: object) -> str:
    """``text`` for a place inside markdown, read as written: ``&`` and ``<`` as entities, other
    punctuation escaped with a backslash, line breaks and control characters as one space (a name
    stays on its line and in its table cell)."""
    words = BREAKS.sub(" ", str(text)).replace("&", "&amp;").replace("<", "&lt;")
    return PUNCTUATION.sub(r"\\\1", words)

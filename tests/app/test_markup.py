"""Issue 50, item 1: user text put into the page's markdown reads as written and starts no markup."""
from __future__ import annotations

import html

import pytest

from app.session.markup import no_html, plain

markdown_it = pytest.importorskip("markdown_it")
HOSTILE = ['<iframe srcdoc="<script>parent.document.title=1337</script>">', "<b id=pwn1>..<img id=pwn2>",
           "*bold* _em_ `code` [link](javascript:alert(1)) ![x](/etc/hostname) &lt;b&gt; \\<i> | cell",
           "line\n# heading\r\n- item"]


def _rendered(markdown: str) -> str:
    return markdown_it.MarkdownIt("commonmark", {"html": True}).enable("table").render(markdown)


@pytest.mark.parametrize("text", HOSTILE)
def test_user_text_is_one_paragraph_of_its_own_words(text: str) -> None:
    rendered = _rendered(plain(text))
    assert rendered.startswith("<p>") and rendered.count("<") == 2, rendered
    assert html.unescape(rendered[3:-5]) == " ".join(text.split("\n")).replace("\r", " ").replace("  ", " ")


@pytest.mark.parametrize("text", HOSTILE)
def test_markdown_given_to_a_panel_holds_no_html_and_no_image(text: str) -> None:
    tokens = markdown_it.MarkdownIt("commonmark", {"html": True}).parse(no_html(f"**Note**: {text}"))
    kinds = {t.type for t in tokens} | {c.type for t in tokens for c in (t.children or [])}
    assert not kinds & {"html_inline", "html_block", "image"}, kinds

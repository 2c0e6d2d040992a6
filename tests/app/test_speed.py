"""Play says how fast it goes when a frame takes longer than the play speed allows (issue 47, item 7)."""
from __future__ import annotations

from app.tab import playing_words


def test_a_play_that_keeps_up_says_nothing_and_one_that_cannot_says_its_rate() -> None:
    assert playing_words(4, 0.2) == "" and playing_words(4, 0.26) == ""
    assert playing_words(4, 0.5) == ("Playing at 2.0 frames/s of the 4 asked: every frame is shown, and each takes "
                                     "0.50 s to compute and show.")
    assert playing_words(1, 1.04) == "" and playing_words(10, 0.2).startswith("Playing at 5.0 frames/s of the 10")

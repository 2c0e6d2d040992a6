"""Which settings two results differ in, in the controls' words: what a stale run and a pinned
baseline say of themselves, and what *jump there* lists before it sets anything."""
from __future__ import annotations

import dataclasses

from app.scene.differences import change_lines, differences, now_words
from app.session.settings import Settings


def test_frame_view_and_unused_methods_do_not_count_and_the_rest_is_named_with_units() -> None:
    settings = Settings()
    assert differences(settings, dataclasses.replace(settings, frame=7).with_view(ghosts=True)) == []
    assert differences(settings, settings.with_params("icp", max_iterations=3)) == []
    other = settings.with_scenario(sigma_p=0.9, seed=3).with_params("cbm", sigma2=5.0)
    found = differences(settings, other)
    assert [d.label for d in found] == ["σ2 distance (m)", "position noise σp (m)", "seed"]
    assert now_words(found) == "σ2 distance (m) 3 (now 5), position noise σp (m) 0.2 (now 0.9), seed 0 (now 3)"
    assert change_lines(found).splitlines()[0] == "- σ2 distance (m): 5 → 3"


def test_a_change_of_method_names_both_methods_and_the_cav() -> None:
    settings = Settings()
    other = dataclasses.replace(settings, method="icp", cav="42")
    labels = [d.label for d in differences(settings, other)]
    assert labels[0] == "method" and labels[-1] == "CAV"

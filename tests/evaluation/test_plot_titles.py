"""evaluate.py's plots say what they show: a title naming each dataset with its frames, and the protocol."""
from __future__ import annotations

import matplotlib.figure
import pytest

from evaluation.cli import main
from evaluation.plots import plot_success_curve, run_title, titled


def test_the_title_names_the_datasets_their_frames_and_the_protocol() -> None:
    title = run_title([("synthetic:40", [0, 1, 2, 3, 10]), ("argoverse2", [5])], "sind")
    assert title == "synthetic:40, 5 frames (0-3, 10); argoverse2, 1 frame (5) · protocol sind"
    figure = titled(plot_success_curve([]), title + " and a long tail " * 5)
    assert "protocol sind" in figure._suptitle.get_text().replace("\n", " ")


def test_every_plot_of_a_run_is_titled(tmp_path, monkeypatch: pytest.MonkeyPatch) -> None:
    titles: dict[str, str] = {}
    save = matplotlib.figure.Figure.savefig

    def recording(figure, path, *args, **kwargs):
        titles[str(path).rsplit("/", 1)[-1]] = figure._suptitle.get_text().replace("\n", " ")
        return save(figure, path, *args, **kwargs)

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", recording)
    args = ["--dataset", "synthetic:40", "--frames", "0:20:10", "--protocol", "sind", "--methods", "cbm",
            "--grid", "eta=0.4,0.8", "--no-timing", "--out", str(tmp_path / "out")]
    assert main(args) == 0
    assert set(titles) == {"rre_rte.png", "success_curve.png", "precision_vs_eta.png"}
    assert all(t == "synthetic:40, 2 frames (0, 10) · protocol sind" for t in titles.values()), titles

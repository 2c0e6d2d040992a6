"""Export: per-frame metrics read back, the preset file loads back through app.presets."""
from __future__ import annotations

import dataclasses
import io

import numpy as np
import polars as pl

from app.session import export
from app.session.explorer import Explorer
from app.session.presets import read
from app.session.sequence import run_sequence
from app.session.settings import Settings


def test_metrics_csv_and_parquet_read_back(small_explorer: Explorer) -> None:
    run = run_sequence(small_explorer, Settings(), frames=range(3))
    for table in (pl.read_csv(io.BytesIO(export.metrics_csv(run.rows))),
                  pl.read_parquet(io.BytesIO(export.metrics_parquet(run.rows)))):
        assert table["frame"].to_list() == [0, 1, 2]
        assert np.allclose(table["rte"].to_numpy(), [row["rte"] for row in run.rows])
        assert table["method"].to_list() == ["cbm"] * 3 and "sigma1" in table.columns


def test_preset_file_loads_back(tmp_path) -> None:
    settings = Settings(frame=7).with_params("cbm", sigma1=12.5, heading="fold")
    settings = dataclasses.replace(settings, method="cbm-no-consensus",
                                   scenario=dataclasses.replace(settings.scenario, protocol="sind", eta=0.35, seed=4))
    path = tmp_path / "exported.toml"
    path.write_bytes(export.preset_toml(settings, "synthetic"))
    preset = read(path, shipped=False)
    assert "synthetic" in preset.description
    assert preset.apply(Settings(frame=7)) == settings


def test_png_encodes_an_image() -> None:
    from PIL import Image

    image = np.zeros((4, 6, 3), np.uint8)
    image[1, 2] = (255, 0, 0)
    decoded = np.asarray(Image.open(io.BytesIO(export.png(image))))
    assert decoded.shape == (4, 6, 3) and tuple(decoded[1, 2]) == (255, 0, 0)

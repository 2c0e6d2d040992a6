"""The GUI of one tab: folders and tabs of controls bound to the tab's ``Settings``.

Every control's callback turns its new value into a change of the settings and hands it to the
session, which recomputes; controls never compute anything themselves.
"""
from __future__ import annotations

import dataclasses
import typing
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
import viser
from viser import uplot

from cbm.methods import METHODS

from .settings import AUTO_CAV, LAYOUTS, LINE_PAIRS, Settings

if TYPE_CHECKING:
    from .client import ClientSession

Change = Callable[[Settings], Settings]

SCENARIO_SLIDERS = {
    # field: (label, min, max, step, hint)
    "eta": ("co-visibility eta", 0.0, 1.0, 0.05, "SIND protocol: share of objects both agents see"),
    "sigma_p": ("position noise σp (m)", 0.0, 2.0, 0.05, "detection position noise, std-dev on x and y"),
    "sigma_theta": ("heading noise σθ (°)", 0.0, 30.0, 0.5, "detection heading noise, std-dev"),
    "flip_prob": ("heading flip prob.", 0.0, 1.0, 0.05, "probability a detection faces backwards"),
    "loc_x": ("localization x (m)", 0.0, 15.0, 0.25, "CAV pose error in x: offset (fixed) or std-dev (gaussian)"),
    "loc_y": ("localization y (m)", 0.0, 15.0, 0.25, "CAV pose error in y"),
    "loc_yaw": ("localization yaw (°)", 0.0, 30.0, 0.5, "CAV pose error in yaw"),
    "sensor_range": ("sensor range (m)", 10.0, 150.0, 5.0, "range protocol: what each agent sees"),
}
CBM_SLIDERS = {
    "sigma1": ("σ1 angle (°)", 1.0, 45.0, 0.5, "largest angle between matching context vectors (eq. 7)"),
    "sigma2": ("σ2 L1 (m)", 0.25, 10.0, 0.25, "largest L1 distance between matching context vectors (eq. 7)"),
    "sigma3": ("σ3 voting (m)", 0.25, 10.0, 0.25, "L1 tolerance of the voting sets of the consensus"),
    "distance_limit": ("distance limit (m)", 1.0, 60.0, 1.0, "reject anchors whose pairs are farther apart on average"),
    "refine_gate": ("refine gate (σ)", 1.0, 8.0, 0.25, "re-association gate, in std-devs of the pairs' noise"),
}


class Panels:
    """All controls of one tab, and the outputs it shows (metrics text, plot over frames)."""

    def __init__(self, gui: viser.GuiApi, session: ClientSession, settings: Settings, n_frames: int,
                 preset_names: list[str]) -> None:
        self.gui, self.session = gui, session
        self.metrics = gui.add_markdown("Computing the first frame…")
        self.plot = gui.add_uplot(*_empty_plot(), title="over frames", aspect=2.0,
                                  scales={"x": uplot.Scale(time=False, auto=True), "y": uplot.Scale(auto=False, range=(0.0, 1.0)),
                                          "m": uplot.Scale(auto=True)},
                                  axes=(uplot.Axis(), uplot.Axis(scale="y"), uplot.Axis(scale="m", side=1)))
        with gui.add_folder("Frame", expand_by_default=True):
            self.frame = gui.add_slider("frame", 0, max(n_frames - 1, 0), 1, settings.frame)
            self.step = gui.add_button_group("step", ("◀ prev", "next ▶"))
            self.play = gui.add_checkbox("play", False)
            self.speed = gui.add_slider("speed (frames/s)", 1, 10, 1, 4)
            self.cav = gui.add_dropdown("CAV", (AUTO_CAV,), initial_value=AUTO_CAV, hint="vehicle acting as the CAV")
        self.tabs = tabs = gui.add_tab_group()
        with tabs.add_tab("Scenario"):
            self.protocol = gui.add_dropdown("protocol", ("range", "sind", "opv2v"),
                                             initial_value=settings.scenario.protocol)
            self.localization = gui.add_dropdown("localization error", ("fixed", "gaussian"),
                                                 initial_value=settings.scenario.localization)
            self.scenario = {name: gui.add_slider(label, low, high, step, getattr(settings.scenario, name), hint=hint)
                             for name, (label, low, high, step, hint) in SCENARIO_SLIDERS.items()}
            self.seed = gui.add_number("seed", settings.scenario.seed, min=0, step=1)
        with tabs.add_tab("Method"):
            self.method = gui.add_dropdown("method", tuple(m.label for m in METHODS.values()),
                                           initial_value=METHODS[settings.method].label)
            self.method_folders, self.method_controls = self._method_controls(settings)
        with tabs.add_tab("View"):
            self.layout = gui.add_dropdown("CAV boxes", LAYOUTS, initial_value=settings.view.layout)
            self.ghosts = gui.add_checkbox("ground-truth ghosts", settings.view.ghosts)
            self.lines = gui.add_checkbox("match lines", settings.view.lines)
            self.line_pairs = gui.add_dropdown("CBM's lines", tuple(LINE_PAIRS.values()),
                                               initial_value=LINE_PAIRS[settings.view.line_pairs],
                                               hint="CBM's own pairs (eq. 13), or all pairs after the guided re-association")
            self.labels = gui.add_checkbox("label clicked objects", settings.view.labels)
            self.reset_camera = gui.add_button("reset camera")
            gui.add_markdown("Boxes: **ego** blue, **CAV** orange (faint: before calibration). Lines: "
                             "green right pair, red wrong pair, grey dashed a true pair missed.")
        with tabs.add_tab("Presets"):
            self.preset = gui.add_dropdown("preset", tuple(preset_names) or ("(none)",))
            self.load_preset = gui.add_button("load")
            self.preset_name = gui.add_text("save as", "my-preset")
            self.save_preset = gui.add_button("save current settings")
        self._bind()
        self.show_method(settings.method)

    def _method_controls(self, settings: Settings) -> tuple[dict[str, Any], dict[tuple[str, str], Any]]:
        """A folder per parameter class, holding one control per field (CBM's thresholds as sliders)."""
        folders, controls = {}, {}
        for method, params in settings.method_params.items():
            if not dataclasses.fields(params):
                continue
            with self.gui.add_folder(f"{METHODS[method].label} parameters") as folder:
                folders[method] = folder
                for f in dataclasses.fields(params):
                    controls[(method, f.name)] = self._control(method, f, getattr(params, f.name))
        return folders, controls

    def _control(self, method: str, f: dataclasses.Field, value: Any) -> Any:
        if method == "cbm" and f.name in CBM_SLIDERS:
            label, low, high, step, hint = CBM_SLIDERS[f.name]
            return self.gui.add_slider(label, low, high, step, value, hint=hint)
        if isinstance(value, bool):
            return self.gui.add_checkbox(f.name, value)
        options = typing.get_args(typing.get_type_hints(METHODS[method].params)[f.name])
        if isinstance(value, str) and options:
            return self.gui.add_dropdown(f.name, options, initial_value=value)
        return self.gui.add_number(f.name, value, step=1 if isinstance(value, int) else 0.01)

    def show_method(self, method: str) -> None:
        """Show only the parameters of the selected method."""
        chosen = METHODS[method]
        for name, folder in self.method_folders.items():
            folder.visible = name == chosen.params_key
        for (name, field), control in self.method_controls.items():
            control.visible = name != chosen.params_key or field in chosen.tunable
        self.line_pairs.visible = chosen.explains

    def set_values(self, settings: Settings) -> None:
        """Move every control to ``settings`` (each move reports back as a change, coalesced)."""
        self.protocol.value = settings.scenario.protocol
        self.localization.value = settings.scenario.localization
        for name, slider in self.scenario.items():
            slider.value = getattr(settings.scenario, name)
        self.seed.value = settings.scenario.seed
        self.method.value = METHODS[settings.method].label
        for (method, name), control in self.method_controls.items():
            control.value = getattr(settings.method_params[method], name)
        self.layout.value = settings.view.layout
        self.ghosts.value, self.lines.value, self.labels.value = (settings.view.ghosts, settings.view.lines,
                                                                  settings.view.labels)
        self.line_pairs.value = LINE_PAIRS[settings.view.line_pairs]

    def _bind(self) -> None:
        change = self.session.change
        self.frame.on_update(lambda e: change(lambda s: dataclasses.replace(s, frame=int(self.frame.value))))
        self.step.on_click(lambda e: self.session.step(-1 if e.target.value.startswith("◀") else 1))
        self.play.on_update(lambda e: self.session.set_playing(self.play.value))
        self.cav.on_update(lambda e: change(lambda s: dataclasses.replace(s, cav=self.session.cav_id(self.cav.value))))
        self.protocol.on_update(lambda e: change(lambda s: _scenario(s, protocol=self.protocol.value)))
        self.localization.on_update(lambda e: change(lambda s: _scenario(s, localization=self.localization.value)))
        for name, slider in self.scenario.items():
            slider.on_update(lambda e, n=name, c=slider: change(lambda s: _scenario(s, **{n: float(c.value)})))
        self.seed.on_update(lambda e: change(lambda s: _scenario(s, seed=max(0, int(self.seed.value)))))
        methods = {m.label: m.name for m in METHODS.values()}
        self.method.on_update(lambda e: self._method_changed(methods[self.method.value]))
        for (method, name), control in self.method_controls.items():
            control.on_update(lambda e, m=method, n=name, c=control: change(lambda s: s.with_params(m, **{n: c.value})))
        for name, control in (("layout", self.layout), ("ghosts", self.ghosts), ("lines", self.lines),
                              ("labels", self.labels)):
            control.on_update(lambda e, n=name, c=control: change(lambda s: _view(s, **{n: c.value})))
        line_pairs = {label: key for key, label in LINE_PAIRS.items()}
        self.line_pairs.on_update(lambda e: change(lambda s: _view(s, line_pairs=line_pairs[self.line_pairs.value])))
        self.reset_camera.on_click(lambda e: self.session.reset_camera())
        self.load_preset.on_click(lambda e: self.session.load_preset(self.preset.value))
        self.save_preset.on_click(lambda e: self.session.save_preset(self.preset_name.value))

    def _method_changed(self, method: str) -> None:
        self.show_method(method)
        self.session.change(lambda s: dataclasses.replace(s, method=method))


def _scenario(settings: Settings, **changes: Any) -> Settings:
    return dataclasses.replace(settings, scenario=dataclasses.replace(settings.scenario, **changes))


def _view(settings: Settings, **changes: Any) -> Settings:
    return dataclasses.replace(settings, view=dataclasses.replace(settings.view, **changes))


def _empty_plot() -> tuple[tuple[np.ndarray, ...], tuple[uplot.Series, ...]]:
    series = (uplot.Series(label="frame"), uplot.Series(label="precision", stroke="#1e9c3c", width=2, scale="y"),
              uplot.Series(label="recall", stroke="#3478f6", width=2, scale="y"),
              uplot.Series(label="RTE (m)", stroke="#e1261e", width=2, scale="m"))
    # viser 1.1.1's uPlot never draws data sent to a chart that was created empty: start it with
    # two frames of gaps instead.
    placeholder = (np.array([0.0, 1.0]), *(np.full(2, np.nan) for _ in series[1:]))
    return placeholder, series
